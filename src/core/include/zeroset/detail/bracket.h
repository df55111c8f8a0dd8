#pragma once
// Bracketed refinement of a root of a scalar function of one variable: the one place for it.
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

}  // namespace zeroset::detail
