#pragma once
// The unit sphere as a point set and as a mesh, for the disk and mesh renderers' tests.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "zeroset/mesh/mesh.h"
#include "zeroset/types.h"

namespace zeroset::test {

/// Points on the unit sphere (a Fibonacci lattice) with outward normals.
inline std::vector<Vec3> sphere_points(int n) {
  std::vector<Vec3> p;
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z);
    p.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return p;
}

/// A UV sphere of radius 1, counter-clockwise seen from outside.
inline Mesh uv_sphere(int rings, int segments) {
  Mesh m;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = std::numbers::pi * i / rings, ph = 2 * std::numbers::pi * j / segments;
      m.positions.emplace_back(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph),
                               std::cos(th));
    }
  auto id = [&](int i, int j) { return static_cast<std::uint32_t>(i * segments + j % segments); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

}  // namespace zeroset::test
