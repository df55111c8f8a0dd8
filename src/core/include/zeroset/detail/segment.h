#pragma once
// The point of a line segment nearest to a point: the one place for it (the singular set's
// distances and index, the floaters' curve rails, the mesh's crossings).
#include <algorithm>

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

}  // namespace zeroset::detail
