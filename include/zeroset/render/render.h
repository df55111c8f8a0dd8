#pragma once
/// The CPU renderer (docs/architecture.md, "Modules"): exact ray casting of algebraic surfaces, and
/// shaded point sets and meshes, so every figure can be made without a GPU.
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <span>
#include <stop_token>
#include <vector>

#include "zeroset/io/image.h"
#include "zeroset/mesh/mesh.h"
#include "zeroset/render/lights.h"
#include "zeroset/render/overlay.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

/// Phong material.
struct Material {
  Color diffuse = Color(0.8, 0.42, 0.1);  ///< linear RGB
  double ambient = 0.12;
  double specular = 0.35;
  double shininess = 40;
};

struct RenderOptions {
  int width = 800;
  int height = 800;
  int samples = 1;               ///< anti-aliasing: samples×samples rays per pixel
  std::optional<Camera> camera;  ///< default: the surface's camera
  std::vector<Light> lights;     ///< empty: default_lights(), a rig that follows the camera
  Material front;                ///< the side ∇F points to
  Material back{.diffuse = Color(0.06, 0.12, 0.35)};  ///< the other side, darker (paper's figures)
  Color background = Color(1, 1, 1);  ///< linear RGB (pictures are gamma encoded, 2.2)
  int threads = 0;                    ///< 0: all cores; the picture does not depend on it
  /// Draws the singular set over the picture (overlay.h); without it the picture is exactly
  /// as before. Each sample ray meets the tubes and spheres exactly and keeps the nearest of
  /// them and the surface, so the overlay is anti-aliased with the picture's samples.
  std::optional<SingularOverlay> singular_overlay;
  /// Called now and then with the fraction done (from one thread at a time).
  std::function<void(double)> progress;
};

/// Statistics of one render.
struct RenderStats {
  double seconds = 0;
  long long rays = 0;
  long long hits = 0;
  long long singular_normals = 0;  ///< hits where ∇F vanished and the fallback normal was used
  long long abandoned_rays = 0;    ///< interval path: rays given up at the per-ray budget (misses)
  long long accurate_rays = 0;     ///< exact path: hits placed by the accurate restriction
  int threads = 0;                 ///< worker threads used
  bool exact = false;              ///< polynomial root isolation (else interval arithmetic)

  /// The figures above as the statistics file's keys (with "method" for `exact`), for
  /// `zeroset render --stats` and Python's render statistics alike.
  nlohmann::json to_json() const;
};

/// Ray casts the surface inside its clip. Polynomials: exact restriction to the ray and robust
/// root isolation, rows of rays at a time, each ray's search guided by its neighbours' hits;
/// other expressions: interval arithmetic along the ray (raycast.h). Throws BadInput when the
/// surface has no bounded clip, a parameter has no value or the size or samples are out of
/// range. Returns an empty image when stopped through `stop`. Cost: about a tenth of a
/// microsecond per ray for degree 4 to 6 on one core (an 800×800 picture of the Kummer
/// surface takes about 0.06 s); bands of rows run on `threads` workers.
Image render_surface(const Surface& surface, const RenderOptions& options,
                     RenderStats* stats = nullptr, std::stop_token stop = {});

/// Draws a point set as shaded disks (oriented by `normals`, radius per point), as in the
/// paper's figures 3–5; a disk seen from the side its normal points away from gets the back
/// material. The surface gives the camera and the scene size. Empty `normals`: disks face the
/// camera; empty `radii`: one radius that roughly covers a surface of the scene's size.
/// Throws InvalidArgument when a non-empty span's size differs from positions'. Cost follows
/// the disks' screen area (100,000 disks at 800×800: a few tenths of a second).
Image render_points(const Surface& surface, std::span<const Vec3> positions,
                    std::span<const Vec3> normals, std::span<const double> radii,
                    const RenderOptions& options);

/// Draws a triangle mesh, smooth-shaded with front and back materials; `wireframe` overlays
/// the edges (about one pixel wide). Vertex normals: the mesh's, else ∇F at the vertex, else
/// (where ∇F vanishes) the adjacent faces' normals. Throws InvalidArgument for a vertex index
/// out of range.
Image render_mesh(const Surface& surface, const Mesh& mesh, const RenderOptions& options,
                  bool wireframe = false);

}  // namespace zeroset
