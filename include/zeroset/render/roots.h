#pragma once
/// Robust isolation of the first real root of a univariate polynomial in an interval, the
/// core of exact ray casting (ALGORITHMS §E): Bernstein coefficients on the interval,
/// Descartes' rule of signs with subdivision (Reimers & Seland 2008 style, depth first so the
/// first root is found first), then refinement by the Illinois method. Roots of even
/// multiplicity (a ray tangent to a surface, a squared equation) have no sign change; they are
/// found through a "zero band": an interval is only discarded when its Bernstein hull stays
/// farther than `band` from zero, so a local minimum of |f| that touches zero within rounding
/// is subdivided down to the tolerance and reported.
#include <array>
#include <optional>
#include <span>

namespace zeroset {

/// Tuning of `RootFinder`.
struct RootOptions {
  /// Width, relative to the search interval, at which an interval whose sign pattern is still
  /// ambiguous (a double root or a near touch) is decided by the zero band.
  double tolerance = 1e-10;
  /// Refinement of a simple root stops when the bracket is this narrow, relative to the
  /// search interval.
  double refine_tolerance = 1e-12;
};

/// Counters of one or many searches (for benchmarks and tests).
struct RootStats {
  long long calls = 0;
  long long subdivisions = 0;   ///< de Casteljau splits
  long long refinements = 0;    ///< function evaluations while refining simple roots
  long long band_roots = 0;     ///< roots reported through the zero band (no sign change)
};

/// Finds the smallest root of f(t) = Σ a_k t^k in [t0, t1]. Allocation-free; owns scratch
/// memory, so use one per thread. Cost: O(d²) per subdivision step, typically a few steps.
class RootFinder {
 public:
  /// Highest degree supported (stack scratch); higher degrees throw InvalidArgument.
  static constexpr int kMaxDegree = 31;

  explicit RootFinder(RootOptions options = {}) : options_(options) {}

  /// The first root of Σ coeffs[k] t^k in [t0, t1] (t0 ≤ t1), or nothing.
  /// `band` ≥ 0 is the absolute uncertainty of f's values (see `rounding_band`): a local
  /// minimum of |f| no larger than it counts as a root. Leading zero coefficients are allowed.
  std::optional<double> first_root(std::span<const double> coeffs, double t0, double t1,
                                   double band);

  const RootStats& stats() const { return stats_; }
  void reset_stats() { stats_ = {}; }

 private:
  RootOptions options_;
  RootStats stats_;
};

/// A bound on the rounding error of f(t) for |t| ≤ t_max, from bounds `abs_coeffs[k]` on the
/// magnitude of each coefficient (including the error already in them): a small multiple of
/// machine epsilon times Σ abs_coeffs[k] t_max^k.
double rounding_band(std::span<const double> abs_coeffs, double t_max);

/// Value of Σ coeffs[k] t^k by Horner's rule.
double evaluate_polynomial(std::span<const double> coeffs, double t);

}  // namespace zeroset
