#include "zeroset/render/roots.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "zeroset/error.h"

namespace zeroset {
namespace {

constexpr int kN = RootFinder::kMaxDegree + 1;
// Depth-first subdivision pushes two halves and pops one per level, so the stack never holds
// more than depth + 1 intervals; the tolerance is clamped so the depth stays below this.
constexpr int kMaxStack = 64;
constexpr double kMinTolerance = 1e-15;

/// ratio[d][i][k] = C(i, k) / C(d, k): power to Bernstein coefficients on [0, 1] for
/// degree d, b_i = Σ_{k ≤ i} ratio[d][i][k] g_k. Built once (256 KB; a render touches
/// one degree's 8 KB).
struct BernsteinTable {
  double ratio[kN][kN][kN] = {};
  BernsteinTable() {
    double binom[kN][kN] = {};
    for (int n = 0; n < kN; ++n) {
      binom[n][0] = binom[n][n] = 1;
      for (int k = 1; k < n; ++k) binom[n][k] = binom[n - 1][k - 1] + binom[n - 1][k];
    }
    for (int d = 0; d < kN; ++d)
      for (int i = 0; i <= d; ++i)
        for (int k = 0; k <= i; ++k) ratio[d][i][k] = binom[i][k] / binom[d][k];
  }
};
const BernsteinTable& bernstein_table() {
  static const BernsteinTable table;
  return table;
}

struct Interval {
  double a, c;  // in the unit parameter u of the search interval
  double b[kN];
};

// The helpers below take the degree both as a template argument D (> 0: fixed, so loops
// unroll) and at run time (used when D == 0).
template <int D>
int sign_variations(const double* b, int d_) {
  // Zeros count as positive, which keeps the count branch-free. It can only overcount (a
  // zero between two negatives adds two), never turn a count of 0 or 2 into 1, so "exactly
  // one variation" still proves exactly one root; the callers also require b_0, b_d ≠ 0.
  const int d = D > 0 ? D : d_;
  int v = 0;
  for (int i = 0; i < d; ++i) v += (b[i] < 0) != (b[i + 1] < 0);
  return v;
}

/// Safeguarded Newton on g in [a, c] with g(a) = ga, g(c) = gc of opposite signs: starts at
/// `start` (the regula falsi point when it is outside the bracket), keeps the bracket, and
/// bisects when a Newton step would leave it. Converges quadratically at a simple root.
template <int D>
double refine(const double* g, int d_, double a, double c, double ga, double gc, double tol,
              long long& evaluations, double start = -1) {
  const int d = D > 0 ? D : d_;
  double x = start;
  if (!(x > a && x < c)) x = (a * gc - c * ga) / (gc - ga);
  if (!(x > a && x < c)) x = 0.5 * (a + c);
  double last_step = -1;  // the previous Newton step, -1 after a bisection
  for (int iter = 0; iter < 100; ++iter) {
    double v = g[d], s = 0;
    for (int k = d - 1; k >= 0; --k) {
      s = s * x + v;
      v = v * x + g[k];
    }
    ++evaluations;
    if (v == 0) return x;
    if ((v > 0) == (ga > 0))
      a = x;
    else
      c = x;
    double next = s != 0 ? x - v / s : -1;
    const bool newton = next > a && next < c;
    if (!newton) next = 0.5 * (a + c);
    const double step = std::abs(next - x);
    if (step <= tol || c - a <= tol) return next;
    // Two Newton steps in a row converging quadratically: step ≈ C·last_step², so the error
    // left in `next` is about C·step², with C estimated from the two; stop when that is
    // within the tolerance.
    if (newton && last_step > 0 && step < 0.5 * last_step &&
        step * (step / last_step) * (step / last_step) <= tol)
      return next;
    last_step = newton ? step : -1;
    x = next;
  }
  return x;
}

/// De Casteljau at 1/2: Bernstein coefficients of the two halves. `b` may alias `right`.
/// Kept scalar: vectorized, each level's loads straddle the previous level's scalar stores
/// and stall on store forwarding, which made this loop the hottest spot of a render.
#if defined(__GNUC__) && !defined(__clang__)
#define ZS_NO_VECTORIZE __attribute__((optimize("no-tree-vectorize")))
#else
#define ZS_NO_VECTORIZE
#endif
template <int D>
ZS_NO_VECTORIZE void split_half(const double* b, int d_, double* left, double* right) {
  const int d = D > 0 ? D : d_;
  double tmp[kN];
  for (int i = 0; i <= d; ++i) tmp[i] = b[i];
  for (int r = 0; r <= d; ++r) {
    left[r] = tmp[0];
    right[d - r] = tmp[d - r];
    for (int i = 0; i < d - r; ++i) tmp[i] = 0.5 * (tmp[i] + tmp[i + 1]);
  }
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

/// Polishes a root u_root of g found in double precision. An even-multiplicity root (a
/// tangent ray, a squared equation) is not seen exactly: rounding turns it into a band where
/// |g| ≤ band, or a pair of close simple roots, and the root found is off by about
/// sqrt(band / g''). The true root is the local extremum of g that follows within the band,
/// where g' changes sign: searched with doubling steps while |g| stays within the band (or
/// still decreases), then refined. A simple root leaves the band after the first step and
/// stays where it is.
template <int D>
double polish_even_root(const double* g, int d_, double u_root, double band, double step,
                        double tol, long long& evaluations) {
  const int d = D > 0 ? D : d_;
  double dg[kN];
  for (int k = 1; k <= d; ++k) dg[k - 1] = k * g[k];
  double prev_value, prev_slope;
  horner2<D>(g, d, u_root, prev_value, prev_slope);
  if (prev_slope == 0) return u_root;
  double prev = u_root;
  // A simple root leaves the band within about band / |g'|: the first step goes twice as
  // far, so a simple root costs one evaluation. An even root's neighbouring extremum lies
  // within sqrt(band / g''), which this step reaches or the doubling steps do.
  step = std::clamp(2 * band / std::abs(prev_slope), step, 1e-3);
  for (int i = 0; i < 64 && prev < 1.0; ++i, step *= 2) {
    const double u = std::min(1.0, u_root + step);
    double gv, gs;
    horner2<D>(g, d, u, gv, gs);
    ++evaluations;
    if (gs == 0) return u;
    if ((gs > 0) != (prev_slope > 0))
      return refine<(D > 1 ? D - 1 : 0)>(dg, d - 1, prev, u, prev_slope, gs, tol, evaluations);
    // Outside the band and moving away from zero: no even root here.
    if (std::abs(gv) > band && std::abs(gv) >= std::abs(prev_value)) break;
    prev = u;
    prev_value = gv;
    prev_slope = gs;
  }
  return u_root;
}

/// The search of RootFinder::first_root for a polynomial of degree d ≥ 1 (fixed when D > 0).
template <int D>
std::optional<double> isolate(const double* coeffs, int d_, double t0, double t1, double band,
                              const RootOptions& options, RootStats& stats) {
  const int d = D > 0 ? D : d_;
  // g(u) = f(t0 + u w), u in [0, 1]: Taylor shift by t0, then scale by powers of w.
  const double w = t1 - t0;
  double g[kN];
  for (int k = 0; k <= d; ++k) g[k] = coeffs[k];
  for (int i = 0; i < d; ++i)
    for (int k = d - 1; k >= i; --k) g[k] += t0 * g[k + 1];
  double wk = 1;
  for (int k = 0; k <= d; ++k) {
    g[k] *= wk;
    wk *= w;
  }

  Interval stack[kMaxStack];
  int top = 0;
  {
    Interval& root = stack[top++];
    root.a = 0;
    root.c = 1;
    const auto& ratio = bernstein_table().ratio[d];
    for (int i = 0; i <= d; ++i) {
      double s = 0;
      for (int k = 0; k <= i; ++k) s += ratio[i][k] * g[k];
      root.b[i] = s;
    }
  }
  const double leaf = std::max(options.tolerance, kMinTolerance);
  const double rtol = std::max(options.refine_tolerance, 0.25 * kMinTolerance);
  auto to_t = [&](double u) { return std::clamp(t0 + u * w, t0, t1); };
  auto polished = [&](double u) {
    return to_t(polish_even_root<D>(g, d, u, band, leaf, rtol, stats.refinements));
  };

  while (top > 0) {
    Interval& iv = stack[--top];
    double lo = iv.b[0], hi = iv.b[0];
    for (int i = 1; i <= d; ++i) {
      lo = std::min(lo, iv.b[i]);
      hi = std::max(hi, iv.b[i]);
    }
    // Convex hull property: the graph lies within [lo, hi] on this interval.
    if (lo > band || hi < -band) continue;

    const double b0 = iv.b[0], bd = iv.b[d];
    const int v = sign_variations<D>(iv.b, d);
    if (v == 1 && b0 != 0 && bd != 0) {
      // Exactly one simple root inside (Descartes), bracketed by the end values.
      return polished(refine<D>(g, d, iv.a, iv.c, b0, bd, rtol, stats.refinements,
                             control_polygon_root<D>(iv.b, d, iv.a, iv.c)));
    }
    if (b0 == 0) return polished(iv.a);
    if (iv.c - iv.a <= leaf) {
      // Too narrow to separate further: either roots too close to tell apart, or |f| touching
      // zero within rounding (an even-multiplicity root). Both are a hit here.
      if ((b0 > 0) != (bd > 0))
        return polished(refine<D>(g, d, iv.a, iv.c, b0, bd, rtol, stats.refinements));
      ++stats.band_roots;
      return polished(iv.a);
    }

    // De Casteljau at the midpoint. `iv` is stack[top]: it is overwritten by the right half,
    // and the left half goes above it so that it is processed first.
    ZS_ASSERT(top + 2 <= kMaxStack);
    ++stats.subdivisions;
    const double a = iv.a, c = iv.c, m = 0.5 * (a + c);
    Interval& right = stack[top];
    Interval& left = stack[top + 1];
    split_half<D>(iv.b, d, left.b, right.b);
    right.a = m;
    right.c = c;
    left.a = a;
    left.c = m;
    top += 2;
  }
  return std::nullopt;
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

std::optional<double> RootFinder::first_root(std::span<const double> coeffs, double t0,
                                             double t1, double band) {
  ++stats_.calls;
  int d = static_cast<int>(coeffs.size()) - 1;
  while (d >= 0 && coeffs[static_cast<size_t>(d)] == 0) --d;
  if (d > kMaxDegree)
    throw InvalidArgument("polynomial degree", std::to_string(d),
                          "ray casting supports degree up to " + std::to_string(kMaxDegree));
  if (!(t1 >= t0)) return std::nullopt;
  if (d <= 0) {
    // A constant: the whole interval lies in the zero set when it is (nearly) zero.
    const double c = d < 0 ? 0.0 : coeffs[0];
    if (std::abs(c) <= band) return t0;
    return std::nullopt;
  }

  switch (d) {
    case 1: return isolate<1>(coeffs.data(), d, t0, t1, band, options_, stats_);
    case 2: return isolate<2>(coeffs.data(), d, t0, t1, band, options_, stats_);
    case 3: return isolate<3>(coeffs.data(), d, t0, t1, band, options_, stats_);
    case 4: return isolate<4>(coeffs.data(), d, t0, t1, band, options_, stats_);
    case 5: return isolate<5>(coeffs.data(), d, t0, t1, band, options_, stats_);
    case 6: return isolate<6>(coeffs.data(), d, t0, t1, band, options_, stats_);
    case 8: return isolate<8>(coeffs.data(), d, t0, t1, band, options_, stats_);
    default: return isolate<0>(coeffs.data(), d, t0, t1, band, options_, stats_);
  }
}

}  // namespace zeroset
