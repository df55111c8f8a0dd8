#pragma once
/// Triangle meshes: a struct of vectors; algorithms are free functions.
#include <array>
#include <cstdint>
#include <vector>

#include "zeroset/surface/singular_kinds.h"
#include "zeroset/types.h"

namespace zeroset {

/// A singular curve of the surface carried by a mesh as a chain of its vertices
/// (docs/meshing.md, "Crossings"). The edges of a crossing curve are shared by the triangles of
/// every sheet through it (four on a double curve, six on a triple line); an isolated curve (a
/// real curve with no sheet through it) has no triangles and is written as a polyline.
struct MeshCurve {
  CurveKind kind = CurveKind::kCrossing;
  std::vector<std::uint32_t> vertices;  ///< at least two; the last equals the first when closed
  bool closed = false;
};

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise seen from +∇F side
  std::vector<std::uint8_t> is_boundary;                ///< per vertex: lies on the clip surface
  std::vector<Vec3> normals;      ///< per vertex, optional (empty or unit ∇F/|∇F|)
  std::vector<MeshCurve> curves;  ///< singular curves through the vertices, may be empty

  size_t vertex_count() const { return positions.size(); }
  size_t triangle_count() const { return triangles.size(); }
  bool empty() const { return triangles.empty(); }
};

}  // namespace zeroset
