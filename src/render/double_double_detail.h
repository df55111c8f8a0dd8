#pragma once
// Double-double arithmetic: a value hi + lo with |lo| ≤ ulp(hi)/2, about 32 significant digits,
// built from error-free transformations (Dekker, Knuth; fused multiply-add for products). The
// ray caster's accurate path restricts F to a ray with it (raycast_accurate.cpp). Private to
// the render module.
#include <cmath>

namespace zeroset::detail {

struct DoubleDouble {
  double hi = 0, lo = 0;
};

/// a + b exactly, for |a| ≥ |b| or a = 0.
inline DoubleDouble quick_two_sum(double a, double b) {
  const double s = a + b;
  return {s, b - (s - a)};
}

/// a + b exactly, whatever their sizes.
inline DoubleDouble two_sum(double a, double b) {
  const double s = a + b;
  const double v = s - a;
  return {s, (a - (s - v)) + (b - v)};
}

/// a · b exactly.
inline DoubleDouble two_prod(double a, double b) {
  const double p = a * b;
  return {p, std::fma(a, b, -p)};
}

/// a + b, with an error of a few units of 2^-104 times |a| + |b|.
inline DoubleDouble operator+(const DoubleDouble& a, const DoubleDouble& b) {
  DoubleDouble s = two_sum(a.hi, b.hi);
  s.lo += a.lo + b.lo;
  return quick_two_sum(s.hi, s.lo);
}

inline DoubleDouble operator*(const DoubleDouble& a, const DoubleDouble& b) {
  DoubleDouble p = two_prod(a.hi, b.hi);
  p.lo += std::fma(a.hi, b.lo, a.lo * b.hi);
  return quick_two_sum(p.hi, p.lo);
}

inline DoubleDouble operator*(const DoubleDouble& a, double b) {
  DoubleDouble p = two_prod(a.hi, b);
  p.lo = std::fma(a.lo, b, p.lo);
  return quick_two_sum(p.hi, p.lo);
}

/// The double nearest to a (within rounding of hi + lo).
inline double to_double(const DoubleDouble& a) { return a.hi + a.lo; }

/// 2^-104 and a bit: the relative rounding of each operation above.
inline constexpr double kDoubleDoubleEpsilon = 4.93e-32;

}  // namespace zeroset::detail
