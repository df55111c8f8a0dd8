#pragma once
/// Expanded polynomials in x, y, z with numeric coefficients, and univariate restriction.
#include <span>
#include <string>
#include <vector>

#include "zeroset/types.h"

namespace zeroset {

/// One term c · x^i y^j z^k.
struct Monomial {
  int i = 0, j = 0, k = 0;
  double c = 0;
  int degree() const { return i + j + k; }
};

/// A polynomial in x, y, z: sparse, terms unique and sorted (by degree, then i, j, k),
/// zero coefficients dropped.
class Polynomial {
 public:
  Polynomial() = default;
  explicit Polynomial(std::vector<Monomial> terms);  ///< merges duplicates, drops zeros

  const std::vector<Monomial>& terms() const { return terms_; }
  int degree() const;  ///< -1 for the zero polynomial
  bool is_zero() const { return terms_.empty(); }

  double value(const Vec3& p) const;
  double value_gradient(const Vec3& p, Vec3& gradient) const;

  /// Coefficients a_0..a_d (d = degree(), ascending) of f(t) = F(o + t·d). Exact up to
  /// rounding. `out` must have degree()+1 entries (else InvalidArgument). Allocation-free up
  /// to degree 32; cost O(terms · degree²) at worst, a few hundred ns for a quartic.
  void restrict_to_line(const Vec3& o, const Vec3& d, std::span<double> out) const;
  std::vector<double> restrict_to_line(const Vec3& o, const Vec3& d) const;

  /// G(p) = F(p + o): the same surface in coordinates centred at o.
  Polynomial translated(const Vec3& o) const;
  /// Scales every coefficient so that the largest magnitude is 1 (same zero set).
  Polynomial normalized() const;

  std::string to_string() const;  ///< e.g. "x^2 + y^2 - 1"

 private:
  std::vector<Monomial> terms_;
};

}  // namespace zeroset
