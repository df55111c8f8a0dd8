#pragma once
/// Value types shared by every zeroset module.
#include <Eigen/Core>
#include <array>
#include <cstdint>

namespace zeroset {

using Vec2 = Eigen::Vector2d;
using Vec3 = Eigen::Vector3d;
using Vec3f = Eigen::Vector3f;
using Mat3 = Eigen::Matrix3d;

/// Axis-aligned box [lo, hi]. An empty box has lo > hi in some coordinate.
struct Box3 {
  Vec3 lo{0, 0, 0};
  Vec3 hi{0, 0, 0};

  /// The cube [-half, half]^3 around the origin.
  static Box3 cube(double half) { return {Vec3::Constant(-half), Vec3::Constant(half)}; }
  Vec3 center() const { return 0.5 * (lo + hi); }
  Vec3 size() const { return hi - lo; }
  double diagonal() const { return (hi - lo).norm(); }
  bool is_empty() const { return (lo.array() > hi.array()).any(); }
  bool contains(const Vec3& p) const {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  }
};

/// The most worker threads a caller may ask for (`--threads`, `threads=`, options' `threads`;
/// 0 means one per core).
inline constexpr int kMaxThreads = 1024;

/// Linear RGB colour with components in [0, 1].
using Color = Eigen::Vector3d;

}  // namespace zeroset
