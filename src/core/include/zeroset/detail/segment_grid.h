#pragma once
// Nearest points on a set of line segments (polylines), the one place for it: the closest
// point of one segment, and a uniform hash grid over many segments for queries within a
// radius (the singular set's distance, the mesh's cut around crossing curves).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <vector>

#include "zeroset/types.h"

namespace zeroset::detail {

// Parameter in [0, 1] of the point of segment [a, b] nearest to p.
inline double segment_parameter(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double l2 = d.squaredNorm();
  return l2 > 0 ? std::clamp((p - a).dot(d) / l2, 0.0, 1.0) : 0.0;
}

inline double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  return (p - (a + segment_parameter(p, a, b) * (b - a))).norm();
}

// Segments in a hash grid of cubes of side `cell`; a segment is filed in every cell its box
// (grown by half a cell) meets. nearest() looks `rings` cells around the query's cell, so it
// finds every segment within rings × cell of p.
class SegmentGrid {
 public:
  struct Hit {
    std::uint32_t segment = 0xffffffffu;
    double t = 0;  // along the segment, [0, 1]
    double distance = std::numeric_limits<double>::infinity();
    bool found() const { return segment != 0xffffffffu; }
  };

  SegmentGrid(double cell) : cell_(cell) {}

  void add(const Vec3& a, const Vec3& b) {
    const std::uint32_t id = static_cast<std::uint32_t>(ends_.size());
    ends_.push_back({a, b});
    const Vec3 lo = a.cwiseMin(b).array() - 0.5 * cell_, hi = a.cwiseMax(b).array() + 0.5 * cell_;
    const auto l = key3(lo), h = key3(hi);
    for (long long i = l[0]; i <= h[0]; ++i)
      for (long long j = l[1]; j <= h[1]; ++j)
        for (long long k = l[2]; k <= h[2]; ++k) cells_[pack(i, j, k)].push_back(id);
  }

  size_t size() const { return ends_.size(); }
  const Vec3& start(std::uint32_t s) const { return ends_[s][0]; }
  const Vec3& end(std::uint32_t s) const { return ends_[s][1]; }

  Hit nearest(const Vec3& p, int rings = 1) const {
    Hit best;
    const auto c = key3(p);
    for (long long i = c[0] - rings; i <= c[0] + rings; ++i)
      for (long long j = c[1] - rings; j <= c[1] + rings; ++j)
        for (long long k = c[2] - rings; k <= c[2] + rings; ++k) {
          const auto it = cells_.find(pack(i, j, k));
          if (it == cells_.end()) continue;
          for (std::uint32_t s : it->second) {
            const double t = segment_parameter(p, ends_[s][0], ends_[s][1]);
            const double d = (p - (ends_[s][0] + t * (ends_[s][1] - ends_[s][0]))).norm();
            if (d < best.distance || (d == best.distance && s < best.segment)) best = {s, t, d};
          }
        }
    return best;
  }

 private:
  std::array<long long, 3> key3(const Vec3& p) const {
    return {static_cast<long long>(std::floor(p.x() / cell_)),
            static_cast<long long>(std::floor(p.y() / cell_)),
            static_cast<long long>(std::floor(p.z() / cell_))};
  }
  static std::uint64_t pack(long long i, long long j, long long k) {
    constexpr long long kOff = 1 << 20;
    return (static_cast<std::uint64_t>(i + kOff) & 0x1fffff) |
           ((static_cast<std::uint64_t>(j + kOff) & 0x1fffff) << 21) |
           ((static_cast<std::uint64_t>(k + kOff) & 0x1fffff) << 42);
  }
  double cell_;
  std::vector<std::array<Vec3, 2>> ends_;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> cells_;
};

}  // namespace zeroset::detail
