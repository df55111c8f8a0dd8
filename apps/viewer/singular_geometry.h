#pragma once
// The singular-set overlay as triangles for OpenGL: the curves as tubes, the special points as
// spheres, with the radii and colours of the CPU renderer's overlay (zeroset/render/overlay.h).
// Plain arrays, no GL: the GL view uploads them, tests check them without a window.
#include <cstdint>
#include <vector>

#include "zeroset/render/overlay.h"

namespace zeroset::viewer {

/// Indexed triangles grouped by colour.
struct OverlayGeometry {
  /// The triangles [first, first + count) of `indices` (counts of indices, not triangles)
  /// have this colour (linear RGB).
  struct Batch {
    Color color;
    std::uint32_t first = 0;
    std::uint32_t count = 0;
  };
  std::vector<float> vertices;  ///< x, y, z, then the unit outward normal, per vertex
  std::vector<std::uint32_t> indices;
  std::vector<Batch> batches;

  std::size_t vertex_count() const { return vertices.size() / 6; }
};

/// Tubes around `set`'s curves and spheres at its points, sized and coloured as `style` says
/// (its `set` is not used) for a scene of radius `scene_radius`. Runs of nearly collinear curve
/// vertices share one tube segment, so a long straight curve costs a few triangles. Non-finite
/// vertices are skipped. Throws InvalidArgument for a bad radius in `style`.
OverlayGeometry singular_overlay_geometry(const SingularSet& set, const SingularOverlay& style,
                                          double scene_radius);

}  // namespace zeroset::viewer
