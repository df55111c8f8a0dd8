#pragma once
/// How well a point set samples a surface (docs/algorithms.md F.2): residual, spacing
/// regularity, covering radius, coverage of known singular points, and the density of samples
/// near the singular set (self-intersection curves, cusps) relative to elsewhere.
#include <cstddef>
#include <cstdint>
#include <span>
#include <stop_token>
#include <vector>

#include "zeroset/surface/analysis.h"
#include "zeroset/surface/singular_set.h"
#include "zeroset/surface/surface.h"
#include "zeroset/types.h"

namespace zeroset {

struct ReferenceOptions {
  std::size_t count = 20000;  ///< points wanted
  std::uint64_t seed = 1;     ///< fixed, so metrics are reproducible
  /// Half thickness of the shell |F|/|∇F| < shell kept from uniform random points in the clip
  /// volume, in world units. 0: scene_radius/200.
  double shell = 0;
  /// Uniform candidates tried at most (the budget when the surface is small or empty).
  /// 0: 400·count.
  std::size_t max_candidates = 0;
  /// Once requested, no further round of candidates is drawn: the result holds what was found
  /// (and the area estimated from the candidates drawn so far).
  std::stop_token stop = {};
};

/// A dense reference sampling of F = 0 inside the clip.
struct ReferenceSampling {
  std::vector<Vec3> points;  ///< on F = 0 (Newton-projected, |F|/|∇F| < 1e-9·scene radius)
  /// Area of F = 0 inside the clip, estimated from the fraction of uniform candidates in the
  /// shell (first order: overestimated where ∇F vanishes along the surface).
  double area = 0;
  std::size_t candidates = 0;  ///< uniform candidates drawn
};

/// Uniform random points in the clip volume are kept when they lie in a thin shell around
/// F = 0 and projected onto it by Newton's method, so the result is close to uniform in area
/// (exactly so to first order, away from singular points). Deterministic for a given seed,
/// whatever the number of threads. Cost: about max(count·V/(2·shell·A), …) field evaluations
/// for clip volume V and area A; tens of milliseconds for 20,000 points on the Kummer scene.
/// Throws BadInput when the clip is unbounded.
ReferenceSampling reference_sampling(const Surface& surface, const ReferenceOptions& options = {});

/// Area of F = 0 inside the clip (reference_sampling with a coarser budget). 0 when empty; a
/// rough figure when `stop` was requested during the estimate.
double estimate_area(const Surface& surface, std::uint64_t seed = 1, std::stop_token stop = {});

// singular_distance(), which the band density uses, is in zeroset/surface/analysis.h.

struct MetricsOptions {
  /// Radius of the balls around known singular points left out of the residual statistics,
  /// where |F|/|∇F| means nothing. 0: the mean nearest-neighbour spacing.
  double singular_exclusion = 0;
  /// The local mean spacing at a singular point is the mean nearest-neighbour distance of this
  /// many samples nearest to it.
  int local_neighbours = 8;
  ReferenceOptions reference = {};  ///< for the covering radius and the band density
  bool covering = true;             ///< compute the covering radius (needs the reference sampling)
  /// Half width of the band around the singular set for band_density_ratio (distance from
  /// singular_distance). 0: not computed.
  double band_halfwidth = 0;
};

/// Coverage of one known singular point.
struct SingularCoverage {
  Vec3 point = Vec3::Zero();
  double distance = 0;       ///< to the nearest sample
  double local_spacing = 0;  ///< mean nearest-neighbour distance of the samples around it
  double ratio = 0;          ///< distance / local_spacing
};

struct SampleMetrics {
  std::size_t count = 0;
  double residual_median = 0;  ///< |F|/|∇F| over samples outside the exclusion balls
  double residual_max = 0;
  std::size_t residual_excluded = 0;  ///< samples inside the exclusion balls
  double spacing_mean = 0;            ///< mean nearest-neighbour distance
  double spacing_cv = 0;              ///< its coefficient of variation (std / mean)
  double covering_radius = 0;    ///< largest distance from a reference point to the nearest sample
  double covering_relative = 0;  ///< covering_radius / spacing_mean
  std::size_t reference_count = 0;
  std::vector<SingularCoverage> singular;  ///< one per known singular point inside the clip
  double singular_ratio_max = 0;           ///< largest SingularCoverage::ratio (0 when none)
  /// (samples in the band / reference points in the band) divided by the same ratio outside
  /// the band: 1 for a sampling as dense near the singular set as elsewhere, < 1 when a gap
  /// opens along it, > 1 when it is denser there. 0 when not computed or the band is empty.
  double band_density_ratio = 0;
  std::size_t band_samples = 0;    ///< samples in the band
  std::size_t band_reference = 0;  ///< reference points in the band
};

/// Measures `samples` on `surface` (current parameters, clip). Deterministic. Cost: O(n) with
/// a spatial hash, plus the reference sampling when covering or band metrics are asked for.
/// Throws BadInput when the clip is unbounded and a reference sampling is needed.
SampleMetrics measure_samples(const Surface& surface, std::span<const Vec3> samples,
                              const MetricsOptions& options = {});

}  // namespace zeroset

namespace zeroset {

/// How a point set covers a singular set found by find_singular_set: each special point and
/// each curve, measured against the local spacing of the samples off the set (the mean
/// nearest-neighbour distance, among the samples farther than `on_set` from the set, of the
/// `local_neighbours` of them nearest to the place). Samples on the set are left out of the
/// spacing because along a chain of samples on a curve the gaps and the nearest-neighbour
/// distances are the same numbers: the spacing of the sheets around is the measure.
struct SingularSetCoverage {
  /// Per special point (set.points): distance to the nearest sample / local spacing.
  std::vector<double> point_ratio;
  /// Per curve (set.curves): the largest gap along it, twice the largest distance from a
  /// point of the curve to its nearest sample, / the local spacing there.
  std::vector<double> curve_gap;
  double point_ratio_max = 0;
  double curve_gap_max = 0;
};

/// Measures the coverage. `on_set` 0: 1e-9 times the extent of the samples. Curves are probed
/// every tenth of the mean off-set spacing. All zero when there are fewer than two samples
/// off the set.
SingularSetCoverage measure_singular_coverage(const SingularSet& set, std::span<const Vec3> samples,
                                              int local_neighbours = 8, double on_set = 0);

}  // namespace zeroset
