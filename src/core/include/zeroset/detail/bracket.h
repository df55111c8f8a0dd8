#pragma once
// Bracketed refinement of a root of a scalar function of one variable: the one place for it.
// Three forms, each kept with the arithmetic its users' outputs were made with: the Illinois
// bracket on an edge's fraction (the polygonizer), the Illinois method on a ray's parameter
// with undefined values inside (the ray caster) and secant steps alternating with bisection
// (the mesh's cut at the clip).
#include <algorithm>
#include <cmath>

namespace zeroset::detail {

// The sign test of every bracket: NaN counts as positive, so a bracket never loses its sign
// change to an undefined value at one end.
inline bool is_positive(double v) { return !(v < 0); }

// The Illinois variant of regula falsi on one edge, in the edge's fraction s ∈ [0, 1]: the
// bracket [lo, hi] keeps opposite signs, and the end value kept twice in a row is halved so
// the bracket shrinks from both sides. Robust where the surface touches the edge (a double
// root), where Newton's method would crawl.
struct IllinoisBracket {
  double lo = 0, hi = 1, f_lo = 0, f_hi = 0;
  int last_side = 0;

  IllinoisBracket(double fa, double fb) : f_lo(fa), f_hi(fb) {}

  /// Takes F at s (not 0): s replaces the end whose value has f's sign.
  void update(double s, double f) {
    if (is_positive(f) == is_positive(f_hi)) {
      hi = s, f_hi = f;
      if (last_side == 1) f_lo *= 0.5;
      last_side = 1;
    } else {
      lo = s, f_lo = f;
      if (last_side == -1) f_hi *= 0.5;
      last_side = -1;
    }
  }

  /// Where the line through the ends' values crosses zero. Converged, the estimate may round
  /// onto an end: that is fine, so only an estimate outside the closed bracket falls back to
  /// bisection.
  double estimate() const {
    const double n = hi - f_hi * (hi - lo) / (f_hi - f_lo);
    return std::isfinite(n) && n >= std::min(lo, hi) && n <= std::max(lo, hi) ? n : 0.5 * (lo + hi);
  }

  /// Takes F at s (not 0) and returns the next s; sets `done` once s no longer moves.
  double next(double s, double f, bool& done) {
    update(s, f);
    const double n = estimate();
    done = std::abs(n - s) <= 1e-13 || std::abs(hi - lo) <= 1e-15;
    return n;
  }
};

/// The root of a sign change of f on [a, b] (a < b, fa = f(a) and fb = f(b) finite and of
/// opposite signs) by the Illinois method, in t itself, to within tol. Where f is undefined
/// (not finite) inside the bracket, the bracket shrinks towards a, which keeps a defined end.
/// The form the ray caster refines hits of fields that are not polynomials with.
template <class F>
double refine_sign_change(F&& f, double a, double b, double fa, double fb, double tol) {
  int retained = 0;
  for (int iter = 0; iter < 100 && b - a > tol; ++iter) {
    double m = (a * fb - b * fa) / (fb - fa);
    if (!(m > a && m < b)) m = 0.5 * (a + b);
    const double fm = f(m);
    if (fm == 0) return m;
    if (!std::isfinite(fm)) {
      // Undefined inside the bracket: bisect on the side that keeps a defined end.
      b = m;
      continue;
    }
    if ((fm > 0) == (fa > 0)) {
      a = m;
      fa = fm;
      if (retained == 1) fb *= 0.5;
      retained = 1;
    } else {
      b = m;
      fb = fm;
      if (retained == -1) fa *= 0.5;
      retained = -1;
    }
  }
  return 0.5 * (a + b);
}

/// The zero of f on [0, 1] (f(0) = f_lo < 0 < f(1) = f_hi) by secant steps alternating with
/// bisection, so that a one-sided secant cannot stall, to within 1e-15. Suits functions with a
/// bounded slope and kinks (distances to clip spheres and planes), where a regula falsi that
/// keeps one end may crawl.
template <class F>
double secant_bisection(F&& f, double f_lo, double f_hi) {
  double lo = 0, hi = 1;
  for (int it = 0; it < 80 && hi - lo > 1e-15; ++it) {
    double t = lo + (hi - lo) * f_lo / (f_lo - f_hi);
    if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
    // Alternate with bisection so a one-sided secant cannot stall.
    if (it % 2) t = 0.5 * (lo + hi);
    const double g = f(t);
    if (g == 0) return t;
    if (g < 0)
      lo = t, f_lo = g;
    else
      hi = t, f_hi = g;
  }
  return 0.5 * (lo + hi);
}

}  // namespace zeroset::detail
