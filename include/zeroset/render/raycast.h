#pragma once
/// Exact ray casting of one surface from one eye point (DESIGN §5, ALGORITHMS §E).
///
/// Polynomial surfaces: F is translated to the eye once (G(p) = F(eye + p)), so that along a
/// ray eye + t·d the restriction is f(t) = Σ_k t^k G_k(d) with G_k the homogeneous parts of
/// G: per ray only the direction-dependent coefficients are computed. The ray is clipped to
/// the clip volume and the first root in that interval is isolated by `RootFinder`, even
/// roots included. Other expressions (and polynomials above RootFinder::kMaxDegree): interval
/// arithmetic over the field's tape along the ray, subdivided where the enclosure of F
/// contains 0 and F is not provably monotone (enclosure of ∇F·d), then sign-change
/// refinement.
#include <memory>
#include <optional>

#include "zeroset/render/roots.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

struct RaycastOptions {
  RootOptions roots;  ///< for the polynomial path
  /// Interval path: subdivision stops at this width relative to the clipped ray segment; a
  /// leaf with a sign change is refined, one without is dropped (unless F is 0 at its start).
  double interval_tolerance = 1.0 / 8192;
  /// Use the interval path even for polynomials (for tests and comparisons).
  bool force_interval = false;
};

/// One intersection of a ray with the surface.
struct SurfaceHit {
  double t = 0;                ///< ray parameter; distance from the eye for a unit direction
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ(); ///< unit, turned towards the eye
  bool front = true;           ///< the eye is on the side ∇F points to (F > 0 there)
  bool singular = false;       ///< ∇F vanished at the hit: the normal is a fallback
};

/// Casts rays from a fixed eye against a surface inside its clip. Not thread-safe (owns an
/// Evaluator and scratch memory): use one per thread. Construction translates the polynomial
/// (cost O(terms · degree³), well under a millisecond for degree ≤ 8).
class SurfaceRayCaster {
 public:
  /// Throws BadInput when the surface's clip is unbounded or a parameter has no value.
  SurfaceRayCaster(const Surface& surface, const Vec3& eye, const RaycastOptions& options = {});
  ~SurfaceRayCaster();
  SurfaceRayCaster(SurfaceRayCaster&&) noexcept;
  SurfaceRayCaster& operator=(SurfaceRayCaster&&) noexcept;

  /// True when rays are cast exactly (polynomial path).
  bool is_exact() const;

  /// Ray parameter of the first intersection of eye + t·dir (t ≥ 0) inside the clip. `dir`
  /// must have unit length (the rounding bounds of the exact path assume it).
  std::optional<double> first_hit(const Vec3& dir);
  /// The first intersection with its normal and side; false when the ray misses. `dir` must
  /// have unit length.
  bool intersect(const Vec3& dir, SurfaceHit& hit);

  const RootStats& root_stats() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace zeroset
