#include "zeroset/render/roots.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "bernstein_detail.h"
#include "zeroset/error.h"

namespace zeroset {
namespace {

constexpr int kN = RootFinder::kMaxDegree + 1;
// Depth-first subdivision pushes two halves and pops one per level, so the stack never holds
// more than depth + 1 intervals; the tolerance is clamped so the depth stays below this.
constexpr int kMaxStack = 64;
constexpr double kMinTolerance = 1e-15;
// Subdivisions a guided piece may take before the search falls back to the plain one.
constexpr int kGuidedSplits = 8;

// The coefficient arrays below are written one double at a time; vectorized code that reads
// two at once stalls on store forwarding (the load straddles two earlier scalar stores), which
// made these loops the hottest spots of a render. So the search is kept scalar.
#if defined(__GNUC__) && !defined(__clang__)
#define ZS_NO_VECTORIZE __attribute__((optimize("no-tree-vectorize", "no-tree-slp-vectorize")))
#else
#define ZS_NO_VECTORIZE
#endif

// The helpers below take the degree both as a template argument D (> 0: fixed, so loops
// unroll and arrays fit the degree) and at run time (used when D == 0).
template <int D>
constexpr int kCapacity = D > 0 ? D + 1 : kN;

/// Bernstein coefficients of g on [a, c], in the unit parameter u of the search interval.
template <int D>
struct BernsteinPiece {
  double a, c;
  double b[kCapacity<D>];
};

/// g at u by Horner's rule, and its derivative.
template <int D>
inline void horner2(const double* g, int d_, double u, double& value, double& slope) {
  const int d = D > 0 ? D : d_;
  value = g[d];
  slope = 0;
  for (int k = d - 1; k >= 0; --k) {
    slope = slope * u + value;
    value = value * u + g[k];
  }
}

/// Σ_k k(k−1)|g_k| r^(k−2): a bound on |g''| over [−r, r].
template <int D>
double curvature_bound(const double* g, int d_, double r) {
  const int d = D > 0 ? D : d_;
  double m = 0;
  for (int k = d; k >= 2; --k) m = m * r + k * (k - 1) * std::abs(g[k]);
  return m;
}

/// A refined root and g' at the last point evaluated next to it (0 when unknown).
struct Refined {
  double u;
  double slope;
};

/// Safeguarded Newton on g in [a, c] with g(a) = ga, g(c) = gc of opposite signs: starts at
/// `start` (the regula falsi point when it is outside the bracket), keeps the bracket, and
/// bisects when a Newton step would leave it. Converges quadratically at a simple root.
/// `curvature` ≥ |g''| on the bracket: a Newton step dx from x leaves an error of at most
/// curvature·dx² / (2|g'(x)|), so one step from a close start often suffices.
template <int D>
ZS_NO_VECTORIZE Refined refine(const double* g, int d_, double a, double c, double ga, double gc,
                               double tol, double curvature, long long& evaluations,
                               double start = -1) {
  const int d = D > 0 ? D : d_;
  double x = start;
  if (!(x > a && x < c)) x = (a * gc - c * ga) / (gc - ga);
  if (!(x > a && x < c)) x = 0.5 * (a + c);
  const bool a_positive = ga > 0;
  double last_step = -1;  // the previous Newton step, -1 after a bisection
  for (int iter = 0; iter < 100; ++iter) {
    double v, s;
    horner2<D>(g, d, x, v, s);
    ++evaluations;
    if (v == 0) return {x, s};
    if ((v > 0) == a_positive)
      a = x;
    else
      c = x;
    double next = s != 0 ? x - v / s : a - 1;  // (outside the bracket when s = 0)
    const bool newton = next > a && next < c;
    if (!newton) next = 0.5 * (a + c);
    const double step = std::abs(next - x);
    if (step <= tol || c - a <= tol) return {next, s};
    if (newton) {
      if (curvature * step * step <= std::abs(s) * tol) return {next, s};
      // Two Newton steps in a row converging quadratically: step ≈ C·last_step², so the
      // error left in `next` is about C·step², with C estimated from the two.
      if (last_step > 0 && step < 0.5 * last_step &&
          step * (step / last_step) * (step / last_step) <= tol)
        return {next, s};
    }
    last_step = newton ? step : -1;
    x = next;
  }
  return {x, 0};
}

/// De Casteljau at 1/2: Bernstein coefficients of the two halves. `b` may alias `right`.
template <int D>
ZS_NO_VECTORIZE void split_half(const double* b, int d_, double* left, double* right) {
  const int d = D > 0 ? D : d_;
  double tmp[kCapacity<D>];
  for (int i = 0; i <= d; ++i) tmp[i] = b[i];
  for (int r = 0; r <= d; ++r) {
    left[r] = tmp[0];
    right[d - r] = tmp[d - r];
    for (int i = 0; i < d - r; ++i) tmp[i] = 0.5 * (tmp[i] + tmp[i + 1]);
  }
}

/// Bernstein coefficients b of g (power basis in u) on [lo, hi] ⊂ [0, 1]: the power
/// coefficients h of g(lo + v (hi − lo)) in v (Taylor shift, scaling), then
/// b_i = Σ_k C(i, k) h_k / C(d, k), the binomial transform done by repeated sums.
template <int D>
ZS_NO_VECTORIZE void to_bernstein(const double* g, int d_, double lo, double hi, double* b) {
  const int d = D > 0 ? D : d_;
  for (int k = 0; k <= d; ++k) b[k] = g[k];
  if (lo != 0)
    for (int i = 0; i < d; ++i)
      for (int k = d - 1; k >= i; --k) b[k] += lo * b[k + 1];
  const double* inverse = detail::kInverseBinomials[static_cast<size_t>(d)].data();
  const double w = hi - lo;
  double wk = w;
  for (int k = 1; k <= d; ++k) {
    b[k] *= wk * inverse[k];
    wk *= w;
  }
  for (int i = 0; i < d; ++i)
    for (int k = d; k > i; --k) b[k] += b[k - 1];
}

/// Where the Bernstein control polygon of b on [a, c] first crosses zero: it converges to the
/// graph quadratically under subdivision, so this is a close first guess for the root.
template <int D>
double control_polygon_root(const double* b, int d_, double a, double c) {
  const int d = D > 0 ? D : d_;
  for (int i = 0; i < d; ++i)
    if ((b[i] > 0) != (b[i + 1] > 0) && b[i + 1] != 0) {
      const double s = (i + b[i] / (b[i] - b[i + 1])) / d;
      return a + s * (c - a);
    }
  return 0.5 * (a + c);
}

/// Polishes a root u_root of g found in double precision, where g' ≈ `slope`. An
/// even-multiplicity root (a tangent ray, a squared equation) is not seen exactly: rounding
/// turns it into a band where |g| ≤ band, or a pair of close simple roots, and the root found
/// is off by about sqrt(band / g''). The true root is the local extremum of g that follows
/// within the band, where g' changes sign: searched with doubling steps while |g| stays within
/// the band (or still decreases), then refined; a sign change of g met with no extremum is
/// the root. A simple root leaves the band after the first step and stays where it is.
template <int D>
ZS_NO_VECTORIZE double polish_even_root(const double* g, int d_, double u_root, double slope,
                                        double band, double step, double tol, double curvature,
                                        long long& evaluations) {
  const int d = D > 0 ? D : d_;
  // A simple root leaves the band within about band / |g'|: the first step goes twice as
  // far, so a simple root costs one evaluation. An even root's neighbouring extremum lies
  // within sqrt(band / g''), which this step reaches or the doubling steps do.
  // (The division is skipped when its result would be clamped to `step`: the usual simple
  // root, where the band is far narrower than the tolerance.)
  const double reach = 2 * band;
  if (!(reach <= step * std::abs(slope))) step = std::clamp(reach / std::abs(slope), step, 1e-3);
  // g' keeps its sign within |g'| / curvature of the root: when that reaches well past where
  // the search below would stop (g leaves the band within about 2·step, with room for the
  // doubling), the search would meet no extremum and return u_root (up to the tolerance).
  if (std::abs(slope) > 16 * curvature * step) return u_root;
  double prev_value, prev_slope;
  horner2<D>(g, d, u_root, prev_value, prev_slope);
  if (prev_slope == 0) return u_root;
  double prev = u_root;
  struct {
    double a = -1, c = -1, ga = 0, gc = 0;
  } crossing;  // the first sign change of g on the way
  for (int i = 0; i < 64 && prev < 1.0; ++i, step *= 2) {
    const double u = std::min(1.0, u_root + step);
    double gv, gs;
    horner2<D>(g, d, u, gv, gs);
    ++evaluations;
    if (gs == 0) return u;
    if ((gs > 0) != (prev_slope > 0)) {
      double dg[kCapacity<D>];
      for (int k = 1; k <= d; ++k) dg[k - 1] = k * g[k];
      double third = 0;  // Σ k(k−1)(k−2)|g_k|, a bound on the third derivative
      for (int k = 3; k <= d; ++k) third += k * (k - 1) * (k - 2) * std::abs(g[k]);
      return refine<(D > 1 ? D - 1 : 0)>(dg, d - 1, prev, u, prev_slope, gs, tol, third,
                                         evaluations)
          .u;
    }
    if (crossing.c < 0 && prev_value != 0 && gv != 0 && (gv > 0) != (prev_value > 0))
      crossing = {prev, u, prev_value, gv};
    // Outside the band and moving away from zero: no even root here.
    if (std::abs(gv) > band && std::abs(gv) >= std::abs(prev_value)) break;
    prev = u;
    prev_value = gv;
    prev_slope = gs;
  }
  // No extremum within the band. A sign change met on the way is the root: u_root was a
  // point where |g| came within the band before it (a band root declared where a
  // subdivision cut a slope flatter than the rounding), or a root already.
  if (crossing.c >= 0)
    return refine<D>(g, d, crossing.a, crossing.c, crossing.ga, crossing.gc, tol, curvature,
                     evaluations)
        .u;
  return u_root;
}

/// The search of RootFinder::first_root for g(u) = f(t0 + u (t1 − t0)) of degree d ≥ 1 on
/// [0, 1] (fixed when D > 0); NaN when there is no root.
template <int D>
ZS_NO_VECTORIZE double isolate(const double* g, int d_, double t0, double t1, double band,
                               const RootGuess& guess, const RootOptions& options,
                               RootStats& stats) {
  const int d = D > 0 ? D : d_;
  const double w = t1 - t0;

  const double leaf = std::max(options.tolerance, kMinTolerance);
  const double rtol = std::max(options.refine_tolerance, 0.25 * kMinTolerance);
  // A guess splits [0, 1] at its limit: [0, split] is searched first, then [split, 1]. The
  // guided piece must be decided cleanly: a root refined from a single sign variation, or
  // every part discarded by its hull. One that needs a decision at the leaf width (a band
  // root, which the cut could fake where |f| is within the band just before a root beyond
  // `split`) or many subdivisions is abandoned for the plain search of [0, 1].
  double u_guess = -1, split = 1;
  if (guess.t > t0 && guess.t < t1) {  // false for NaN
    ++stats.guided;
    const double inverse_w = 1 / w;
    u_guess = (guess.t - t0) * inverse_w;
    split = std::min(1.0, u_guess + std::max(guess.spread, 0.0) * inverse_w);
  }
  BernsteinPiece<D> stack[kMaxStack];
  for (double lo = 0, hi = split;;) {
    const bool guided = hi < 1;
    // A root refined from the interval iv (start: where Newton begins), then polished.
    auto refined = [&](const BernsteinPiece<D>& iv, double start) {
      stats.guided_roots += guided;
      // |g''| ≤ d(d−1)·max|second difference of the Bernstein coefficients| / (c − a)² on
      // [a, c], or the power form's bound over [0, c]: the smaller. The polish may look
      // beyond c, so it gets the bound over [0, 1].
      const double a = iv.a, c = iv.c;
      double second = 0;
      for (int i = 0; i + 2 <= d; ++i)
        second = std::max(second, std::abs(iv.b[i + 2] - 2 * iv.b[i + 1] + iv.b[i]));
      const double curvature =
          std::min(curvature_bound<D>(g, d, c), d * (d - 1) * second / ((c - a) * (c - a)));
      const Refined r =
          refine<D>(g, d, a, c, iv.b[0], iv.b[d], rtol, curvature, stats.refinements, start);
      const double u = r.slope == 0
                           ? r.u
                           : polish_even_root<D>(g, d, r.u, r.slope, band, leaf, rtol,
                                                 curvature_bound<D>(g, d, 1), stats.refinements);
      return std::clamp(t0 + u * w, t0, t1);
    };
    // A root at u without a sign change around it, polished.
    auto touching = [&](double u) {
      stats.guided_roots += guided;
      double value, slope;
      horner2<D>(g, d, u, value, slope);
      if (slope != 0)
        u = polish_even_root<D>(g, d, u, slope, band, leaf, rtol, curvature_bound<D>(g, d, 1),
                                stats.refinements);
      return std::clamp(t0 + u * w, t0, t1);
    };
    int top = 0;
    {
      BernsteinPiece<D>& piece = stack[top++];
      piece.a = lo;
      piece.c = hi;
      to_bernstein<D>(g, d, lo, hi, piece.b);
    }
    int budget = kGuidedSplits;
    bool abandoned = false;
    while (top > 0) {
      BernsteinPiece<D>& iv = stack[--top];
      const double b0 = iv.b[0], bd = iv.b[d];
      // Convex hull property: the graph lies within the hull of the coefficients, so when
      // they all lie beyond the band on one side there is no root here.
      if (std::abs(b0) > band) {
        int i = 1;
        if (b0 > 0)
          while (i <= d && iv.b[i] > band) ++i;
        else
          while (i <= d && iv.b[i] < -band) ++i;
        if (i > d) continue;
      }
      // Sign variations count zeros as positive, which keeps the count branch-free: it can
      // only overcount (a zero between two negatives adds two), never turn a count of 0 or 2
      // into 1, so "exactly one variation" still proves exactly one root (with b_0, b_d ≠ 0).
      int v = 0;
      for (int i = 1; i <= d; ++i) v += (iv.b[i - 1] < 0) != (iv.b[i] < 0);
      if (v == 1 && b0 != 0 && bd != 0) {
        // Exactly one simple root inside (Descartes), bracketed by the end values; the
        // refinement starts at the guess when it lies inside, else where the control
        // polygon crosses zero.
        const double start = u_guess > iv.a && u_guess < iv.c
                                 ? u_guess
                                 : control_polygon_root<D>(iv.b, d, iv.a, iv.c);
        return refined(iv, start);
      }
      if (b0 == 0) return touching(iv.a);
      if (guided && (iv.c - iv.a <= leaf || --budget < 0)) {
        abandoned = true;
        break;
      }
      if (iv.c - iv.a <= leaf) {
        // Too narrow to separate further: either roots too close to tell apart, or |f|
        // touching zero within rounding (an even-multiplicity root). Both are a hit here.
        if ((b0 > 0) != (bd > 0)) return refined(iv, -1);
        ++stats.band_roots;
        return touching(iv.a);
      }

      // De Casteljau at the midpoint. `iv` is stack[top]: it is overwritten by the right
      // half, and the left half goes above it so that it is processed first.
      ZS_ASSERT(top + 2 <= kMaxStack);
      ++stats.subdivisions;
      const double a = iv.a, c = iv.c, m = 0.5 * (a + c);
      BernsteinPiece<D>& right = stack[top];
      BernsteinPiece<D>& left = stack[top + 1];
      split_half<D>(iv.b, d, left.b, right.b);
      right.a = m;
      right.c = c;
      left.a = a;
      left.c = m;
      top += 2;
    }
    if (abandoned) {
      ++stats.guides_abandoned;
      lo = 0;
      hi = 1;
    } else if (hi < 1) {
      lo = hi;
      hi = 1;
    } else {
      return std::numeric_limits<double>::quiet_NaN();
    }
  }
}

}  // namespace

double evaluate_polynomial(std::span<const double> coeffs, double t) {
  double v = 0;
  for (size_t k = coeffs.size(); k-- > 0;) v = v * t + coeffs[k];
  return v;
}

double rounding_band(std::span<const double> abs_coeffs, double t_max) {
  const double t = std::abs(t_max);
  double s = 0;
  for (size_t k = abs_coeffs.size(); k-- > 0;) s = s * t + std::abs(abs_coeffs[k]);
  // Horner, the shift to the interval and the Bernstein conversion each lose a few ulps per
  // degree; 16 (d + 1) ulps of the magnitude sum covers them with margin.
  const double d = static_cast<double>(abs_coeffs.size());
  return 16.0 * d * std::numeric_limits<double>::epsilon() * s;
}

void shift_to_unit(std::span<const double> coeffs, double t0, double t1, double* g) {
  const int d = static_cast<int>(coeffs.size()) - 1;
  const double w = t1 - t0;
  for (int k = 0; k <= d; ++k) g[k] = coeffs[static_cast<size_t>(k)];
  for (int i = 0; i < d; ++i)
    for (int k = d - 1; k >= i; --k) g[k] = std::fma(t0, g[k + 1], g[k]);
  double wk = w;
  for (int k = 1; k <= d; ++k) {
    g[k] *= wk;
    wk *= w;
  }
}

double RootFinder::find_first_root(std::span<const double> coeffs, double t0, double t1,
                                   double band, const RootGuess& guess) {
  int d = static_cast<int>(coeffs.size()) - 1;
  while (d >= 0 && coeffs[static_cast<size_t>(d)] == 0) --d;
  if (d > kMaxDegree)
    throw InvalidArgument("polynomial degree", std::to_string(d),
                          "ray casting supports degree up to " + std::to_string(kMaxDegree));
  if (!(t1 >= t0)) {
    ++stats_.calls;
    return std::numeric_limits<double>::quiet_NaN();
  }
  if (d <= 0) {
    ++stats_.calls;
    // Every coefficient zero: F vanishes on the whole line (F ≡ 0, or a ray inside a plane).
    // There is no surface point to see along it, only a set the ray runs in: a miss.
    if (d < 0) {
      start_value_ = 0;
      return std::numeric_limits<double>::quiet_NaN();
    }
    // A nonzero constant: the whole interval lies in the zero set when it is nearly zero.
    const double c = coeffs[0];
    start_value_ = c;
    return std::abs(c) <= band ? t0 : std::numeric_limits<double>::quiet_NaN();
  }
  double g[kN];
  shift_to_unit(coeffs.first(static_cast<size_t>(d + 1)), t0, t1, g);
  return find_first_root_on_unit(std::span<const double>(g, static_cast<size_t>(d + 1)), t0, t1,
                                 band, guess);
}

double RootFinder::find_first_root_on_unit(std::span<const double> g, double t0, double t1,
                                           double band, const RootGuess& guess) {
  ++stats_.calls;
  const int d = static_cast<int>(g.size()) - 1;
  ZS_ASSERT(d >= 1 && d <= kMaxDegree && t1 >= t0);
  start_value_ = g[0];
  const double* c = g.data();
  switch (d) {
    case 1:
      return isolate<1>(c, d, t0, t1, band, guess, options_, stats_);
    case 2:
      return isolate<2>(c, d, t0, t1, band, guess, options_, stats_);
    case 3:
      return isolate<3>(c, d, t0, t1, band, guess, options_, stats_);
    case 4:
      return isolate<4>(c, d, t0, t1, band, guess, options_, stats_);
    case 5:
      return isolate<5>(c, d, t0, t1, band, guess, options_, stats_);
    case 6:
      return isolate<6>(c, d, t0, t1, band, guess, options_, stats_);
    case 8:
      return isolate<8>(c, d, t0, t1, band, guess, options_, stats_);
    default:
      return isolate<0>(c, d, t0, t1, band, guess, options_, stats_);
  }
}

}  // namespace zeroset
