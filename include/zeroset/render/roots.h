#pragma once
/// Robust isolation of the first real root of a univariate polynomial in an interval, the
/// core of exact ray casting (docs/algorithms.md E.2): Bernstein coefficients on the interval,
/// Descartes' rule of signs with subdivision (Reimers & Seland 2008 style, depth first so the
/// first root is found first), then refinement by the Illinois method. Roots of even
/// multiplicity (a ray tangent to a surface, a squared equation) have no sign change; they are
/// found through a "zero band": an interval is only discarded when its Bernstein hull stays
/// farther than `band` from zero, so a local minimum of |f| that touches zero within rounding
/// is subdivided down to the tolerance and reported.
#include <array>
#include <cmath>
#include <limits>
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
  long long subdivisions = 0;      ///< de Casteljau splits
  long long refinements = 0;       ///< function evaluations while refining simple roots
  long long band_roots = 0;        ///< roots reported through the zero band (no sign change)
  long long guided = 0;            ///< searches given a usable `RootGuess`
  long long guided_roots = 0;      ///< of those, found before the guess's limit
  long long guides_abandoned = 0;  ///< guided searches that fell back to the plain one
};

/// Where the first root is expected, e.g. from a neighbouring ray (pixel coherence): near
/// `t`, and not beyond `t + spread`. A guess only changes the order of the search, never
/// its result: [t0, t + spread] is searched first, then the rest of the interval, each with
/// the full isolation, so no root is missed whatever the guess. A good guess saves the
/// subdivisions that separate the first root from the later ones, and starts the refinement
/// next to the root.
struct RootGuess {
  double t = std::numeric_limits<double>::quiet_NaN();  ///< NaN: no guess
  double spread = 0;                                    ///< ≥ 0, in the units of t
};

/// Finds the smallest root of f(t) = Σ a_k t^k in [t0, t1]. Allocation-free; owns scratch
/// memory, so use one per thread. Cost: O(d²) per subdivision step, typically a few steps.
class RootFinder {
 public:
  /// Highest degree supported (stack scratch); higher degrees throw InvalidArgument.
  static constexpr int kMaxDegree = 31;

  explicit RootFinder(RootOptions options = {}) : options_(options) {}

  /// The first root of Σ coeffs[k] t^k in [t0, t1] (t0 ≤ t1), or nothing; nothing too when
  /// every coefficient is zero (f vanishes on the whole line: no point of it is singled out).
  /// `band` ≥ 0 is the absolute uncertainty of f's values (see `rounding_band`): a local
  /// minimum of |f| no larger than it counts as a root. Leading zero coefficients are allowed.
  /// `guess` (optional) orders the search; the result does not depend on it beyond the
  /// refinement tolerance.
  std::optional<double> first_root(std::span<const double> coeffs, double t0, double t1,
                                   double band, const RootGuess& guess = {}) {
    const double t = find_first_root(coeffs, t0, t1, band, guess);
    return std::isnan(t) ? std::nullopt : std::optional<double>(t);
  }
  /// The same, with NaN for "no root": cheaper to pass on in tight loops than an optional.
  double find_first_root(std::span<const double> coeffs, double t0, double t1, double band,
                         const RootGuess& guess = {});

  /// The same search for f already written on [t0, t1] (t0 ≤ t1) in the unit parameter:
  /// g(u) = f(t0 + u (t1 − t0)) = Σ g[k] u^k, d = g.size() − 1 ≥ 1, f of degree d exactly, as
  /// made by `shift_to_unit` (callers that set up many rays at once make it themselves).
  double find_first_root_on_unit(std::span<const double> g, double t0, double t1, double band,
                                 const RootGuess& guess = {});

  /// f(t0) of the last search, as computed by it (the first Bernstein coefficient): tells
  /// which side of the surface the interval starts on at no extra cost.
  double start_value() const { return start_value_; }

  const RootStats& stats() const { return stats_; }
  void reset_stats() { stats_ = {}; }

 private:
  RootOptions options_;
  RootStats stats_;
  double start_value_ = 0;
};

/// g[k], k ≤ d = coeffs.size() − 1: the coefficients of g(u) = f(t0 + u (t1 − t0)) from those
/// of f (a Taylor shift by t0 with fused multiply-adds, then a scaling by powers of t1 − t0),
/// the form RootFinder searches. `g` holds coeffs.size() entries. O(d²).
void shift_to_unit(std::span<const double> coeffs, double t0, double t1, double* g);

/// A bound on the rounding error of f(t) for |t| ≤ t_max, from bounds `abs_coeffs[k]` on the
/// magnitude of each coefficient (including the error already in them): a small multiple of
/// machine epsilon times Σ abs_coeffs[k] t_max^k.
double rounding_band(std::span<const double> abs_coeffs, double t_max);

/// Value of Σ coeffs[k] t^k by Horner's rule.
double evaluate_polynomial(std::span<const double> coeffs, double t);

}  // namespace zeroset
