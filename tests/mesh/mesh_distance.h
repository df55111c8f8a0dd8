#pragma once
// Distances from points to a mesh, for the tests that check a mesh against a known surface.
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <vector>

#include "zeroset/mesh/mesh.h"

namespace zeroset::test {

// Closest point of triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
inline Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Primitives (numbered 0 … n−1) binned by their boxes in cubes of side `cell`: the distance
// from a point to the nearest one is exact up to `cell`. `distance_to(i, p)` measures one.
class BoxBins {
 public:
  using Distance = std::function<double(std::uint32_t, const Vec3&)>;
  // box(i) gives primitive i's corners lo, hi.
  BoxBins(std::uint32_t count, const std::function<std::array<Vec3, 2>(std::uint32_t)>& box,
          Distance distance_to, double cell)
      : distance_to_(std::move(distance_to)), cell_(cell) {
    for (std::uint32_t t = 0; t < count; ++t) {
      const auto [lo, hi] = box(t);
      const auto a = key(lo), b = key(hi);
      for (long long i = a[0]; i <= b[0]; ++i)
        for (long long j = a[1]; j <= b[1]; ++j)
          for (long long k = a[2]; k <= b[2]; ++k) bins_[{i, j, k}].push_back(t);
    }
  }
  double distance(const Vec3& p) const {
    double best = std::numeric_limits<double>::infinity();
    const auto c = key(p);
    for (long long i = c[0] - 1; i <= c[0] + 1; ++i)
      for (long long j = c[1] - 1; j <= c[1] + 1; ++j)
        for (long long k = c[2] - 1; k <= c[2] + 1; ++k) {
          const auto it = bins_.find({i, j, k});
          if (it == bins_.end()) continue;
          for (std::uint32_t t : it->second) best = std::min(best, distance_to_(t, p));
        }
    return best;
  }

 private:
  std::array<long long, 3> key(const Vec3& p) const {
    return {static_cast<long long>(std::floor(p.x() / cell_)),
            static_cast<long long>(std::floor(p.y() / cell_)),
            static_cast<long long>(std::floor(p.z() / cell_))};
  }
  Distance distance_to_;
  double cell_;
  std::map<std::array<long long, 3>, std::vector<std::uint32_t>> bins_;
};

// A mesh's triangles in BoxBins.
class TriangleBins : public BoxBins {
 public:
  TriangleBins(const Mesh& m, double cell)
      : BoxBins(
            static_cast<std::uint32_t>(m.triangles.size()),
            [&m](std::uint32_t t) {
              Vec3 lo = m.positions[m.triangles[t][0]], hi = lo;
              for (std::uint32_t v : m.triangles[t])
                lo = lo.cwiseMin(m.positions[v]), hi = hi.cwiseMax(m.positions[v]);
              return std::array<Vec3, 2>{lo, hi};
            },
            [&m](std::uint32_t t, const Vec3& p) {
              const auto& tri = m.triangles[t];
              return (p - closest_on_triangle(p, m.positions[tri[0]], m.positions[tri[1]],
                                              m.positions[tri[2]]))
                  .norm();
            },
            cell) {}
};

inline double mean_edge(const Mesh& m) {
  double sum = 0;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) sum += (m.positions[t[k]] - m.positions[t[(k + 1) % 3]]).norm();
  return sum / (3.0 * static_cast<double>(m.triangles.size()));
}

}  // namespace zeroset::test
