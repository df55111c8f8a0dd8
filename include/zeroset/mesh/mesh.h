#pragma once
/// Triangle meshes: a struct of vectors; algorithms are free functions.
#include <array>
#include <cstdint>
#include <vector>

#include "zeroset/types.h"

namespace zeroset {

struct Mesh {
  std::vector<Vec3> positions;
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise seen from +∇F side
  std::vector<std::uint8_t> is_boundary;                ///< per vertex: lies on the clip surface
  std::vector<Vec3> normals;                            ///< per vertex, optional (empty or unit ∇F/|∇F|)

  size_t vertex_count() const { return positions.size(); }
  size_t triangle_count() const { return triangles.size(); }
  bool empty() const { return triangles.empty(); }
};

}  // namespace zeroset
