#pragma once
/// Exact ray casting of one surface from an eye point, or along parallel rays for an
/// orthographic view (docs/algorithms.md E). Polynomials
/// (up to Field::kMaxExpansionDegree, 24) are restricted exactly to each ray, one row of rays
/// at a time, and the first root inside the clip is isolated by `RootFinder`, even roots
/// included; other expressions go through interval arithmetic along the ray.
#include <memory>
#include <optional>
#include <span>

#include "zeroset/render/roots.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

struct RaycastOptions {
  RootOptions roots;  ///< for the polynomial path
  /// Interval path: subdivision stops at this width relative to the clipped ray segment; a
  /// leaf with a sign change is refined, one without is dropped (unless F is 0 at its start).
  double interval_tolerance = 1.0 / 8192;
  /// Interval path: at most this many interval evaluations per ray. Where F is undefined or
  /// unbounded along a ray (0/0, a pole) the enclosures exclude nothing and the subdivision
  /// would visit every leaf, thousands per ray; a ray that runs out is a miss, counted in
  /// SurfaceRayCaster::abandoned_rays. Rays through defined fields need a few dozen; where
  /// enclosures overflow (degree 1000) a ray in 10,000 needs more.
  int interval_budget = 256;
  /// Use the interval path even for polynomials (for tests and comparisons).
  bool force_interval = false;
};

/// One intersection of a ray with the surface.
struct SurfaceHit {
  double t = 0;  ///< ray parameter: point = eye + t·direction
  Vec3 point = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();  ///< unit, turned towards the eye
  bool front = true;            ///< the eye is on the side ∇F points to (F > 0 there)
  bool singular = false;        ///< ∇F vanished at the hit: the normal is a fallback
};

/// Casts rays from a fixed eye against a surface inside its clip. Not thread-safe (owns an
/// Evaluator and scratch memory): use one per thread. Construction translates the polynomial
/// (cost O(terms · degree³), well under a millisecond for degree ≤ 8). For many rays, cast
/// them in rows (begin_row, intersect_in_row); a single ray is a row of one.
class SurfaceRayCaster {
 public:
  /// Throws BadInput when the surface's clip is unbounded or a parameter has no value.
  SurfaceRayCaster(const Surface& surface, const Vec3& eye, const RaycastOptions& options = {});
  ~SurfaceRayCaster();
  SurfaceRayCaster(SurfaceRayCaster&&) noexcept;
  SurfaceRayCaster& operator=(SurfaceRayCaster&&) noexcept;

  /// True when rays are cast exactly (polynomial path).
  bool is_exact() const;

  /// Ray parameter of the first intersection of eye + t·dir (t ≥ 0) inside the clip; `dir`
  /// is any nonzero direction (t is then in units of its length). Starts a row of one ray
  /// (see begin_row).
  std::optional<double> first_hit(const Vec3& dir);
  /// The first intersection with its normal and side; false when the ray misses.
  bool intersect(const Vec3& dir, SurfaceHit& hit);

  /// Starts a row of rays with directions base + s·step (s real; base + s·step nonzero for
  /// the s used): expands the restriction of F and of its gradient to the row, once, at
  /// O(degree) per monomial of degree ≤ degree and per term of F and ∇F.
  void begin_row(const Vec3& base, const Vec3& step);
  /// Starts a row of parallel rays (an orthographic view): the ray at s starts at
  /// origin + s·origin_step and runs along `dir`, t ≥ 0 in units of |dir|. F is translated to
  /// `origin` (O(terms · degree³), so the eye of later perspective rows moves there too) and
  /// restricted to the row's plane once; each ray then costs what a perspective one does.
  /// Packets are not used (prepare_in_row returns 0); intersect_in_row and first_hit_in_row
  /// cast the row's rays. A translation that overflows sends the caster to interval
  /// arithmetic.
  void begin_parallel_row(const Vec3& origin, const Vec3& origin_step, const Vec3& dir);
  /// The rays of the current row with s outside [s_min, s_max] miss the clip volume (a
  /// conservative range from its spheres; infinite without them, empty when no ray meets it).
  void row_extent(double& s_min, double& s_max) const;
  /// Starts a packet of four rays of the row at s[0..3] (nothing when s has another size).
  /// With AVX2, on the exact path and up to degree 6, their straight-line parts are done four
  /// rays per instruction: here the clip, each ray's polynomial, its rounding band, its
  /// shift to the clipped interval and the first levels of the root isolation, which prove
  /// most misses; in packet_hits the normals. The rest of the root isolation stays per ray,
  /// in intersect_in_row or first_hit_in_row. Every result is the same, bit for bit, as
  /// without packets. Returns the rays found to miss here (bit i: the ray at s[i]), for
  /// which first_hit_in_row and intersect_in_row would report no hit, so callers may skip
  /// them; 0 without AVX2. Valid until the next call or begin_row.
  int prepare_in_row(std::span<const double> s);
  /// The parameter t of the first hit of the row's ray at s, as intersect_in_row, without the
  /// normal: when s is in the packet, the hit is kept for packet_hits. False when it misses.
  bool first_hit_in_row(double s, const RootGuess& guess, double& t);
  /// The hits that first_hit_in_row found for the packet's rays since prepare_in_row, the
  /// same as intersect_in_row gives: bit i of the result is set when hits[i] (the ray at
  /// s[i]) holds one.
  int packet_hits(SurfaceHit (&hits)[4]);
  /// The first intersection of the row's ray eye + t·(base + s·step), t ≥ 0, inside the
  /// clip; `hit.t` is in units of that direction's length. `guess`, e.g. from the neighbouring
  /// rays' hits, only speeds up the search (exact path).
  bool intersect_in_row(double s, SurfaceHit& hit, const RootGuess& guess = {});

  const RootStats& root_stats() const;
  /// Rays of the interval path given up as misses at RaycastOptions::interval_budget.
  long long abandoned_rays() const;
  /// Hits of the exact path that its fast restriction could not place within 1e-9 of the clip
  /// radius, found again from F restricted to the ray in double-double (docs/rendering.md,
  /// "Accuracy").
  long long accurate_rays() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace zeroset
