#pragma once
// The ray tests' independent reference (F restricted to a ray in long double) and random
// cameras around a scene.
#include <cmath>
#include <random>
#include <vector>

#include "zeroset/expr/polynomial.h"
#include "zeroset/render/view.h"
#include "zeroset/types.h"

namespace zeroset::test {

using Real = long double;

/// The slow, independent reference: F restricted to the ray in long double, expanded about
/// the middle of the clipped segment (no cancellation from a far eye), sampled densely;
/// the first sign change is bisected. Rays on which |F| has a local minimum that comes
/// near zero (relative to the size of F's terms there) without a sign change before the
/// first root are near-tangent: the answer is ill-conditioned in double precision, for the
/// reference as much as for the ray caster, so the caller skips them.
struct Reference {
  enum class Kind { kMiss, kHit, kAmbiguous };
  Kind kind = Kind::kMiss;
  double t = 0;
};

class ReferenceCaster {
 public:
  explicit ReferenceCaster(const Polynomial& p) : terms_(p.terms()), degree_(p.degree()) {}

  Reference first_hit(const Vec3& o, const Vec3& d, double t0, double t1) {
    const Real tm = 0.5L * (Real(t0) + Real(t1)), h = 0.5L * (Real(t1) - Real(t0));
    expand(o, d, tm);
    constexpr int kSamples = 2048;
    Real prev = eval(-h);
    Real prev_s = -h;
    Real prev_prev_abs = -1;
    for (int i = 1; i <= kSamples; ++i) {
      const Real s = -h + 2 * h * i / kSamples;
      const Real v = eval(s);
      if (prev == 0) return {Reference::Kind::kHit, double(tm + prev_s)};
      if ((v > 0) != (prev > 0) && v != 0) {
        Real a = prev_s, b = s, fa = prev;
        for (int k = 0; k < 200 && b - a > 1e-16L * (1 + std::abs(tm)); ++k) {
          const Real m = 0.5L * (a + b), fm = eval(m);
          if ((fm > 0) == (fa > 0)) {
            a = m;
            fa = fm;
          } else {
            b = m;
          }
        }
        return {Reference::Kind::kHit, double(tm + 0.5L * (a + b))};
      }
      // A local minimum of |f| at the previous sample: how close does it come to zero?
      if (prev_prev_abs >= 0 && std::abs(prev) <= prev_prev_abs && std::abs(prev) <= std::abs(v) &&
          near_zero_minimum(prev_s - 2 * h / kSamples, s))
        return {Reference::Kind::kAmbiguous, 0};
      prev_prev_abs = std::abs(prev);
      prev = v;
      prev_s = s;
    }
    return {};
  }

 private:
  /// Coefficients of F(o + (tm + s) d) in s, by multiplying out each term in long double.
  void expand(const Vec3& o, const Vec3& d, Real tm) {
    coeffs_.assign(static_cast<size_t>(degree_ + 1), 0);
    abs_coeffs_.assign(coeffs_.size(), 0);
    Real base[3], dir[3];
    for (int k = 0; k < 3; ++k) {
      base[k] = Real(o[k]) + tm * Real(d[k]);
      dir[k] = d[k];
    }
    std::vector<Real> prod, tmp;
    for (const Monomial& m : terms_) {
      prod.assign(1, Real(m.c));
      const int e[3] = {m.i, m.j, m.k};
      for (int axis = 0; axis < 3; ++axis)
        for (int n = 0; n < e[axis]; ++n) {
          tmp.assign(prod.size() + 1, 0);
          for (size_t q = 0; q < prod.size(); ++q) {
            tmp[q] += prod[q] * base[axis];
            tmp[q + 1] += prod[q] * dir[axis];
          }
          prod.swap(tmp);
        }
      for (size_t q = 0; q < prod.size(); ++q) {
        coeffs_[q] += prod[q];
        abs_coeffs_[q] += std::abs(prod[q]);
      }
    }
  }
  Real eval(Real s) const {
    Real v = 0;
    for (size_t k = coeffs_.size(); k-- > 0;) v = v * s + coeffs_[k];
    return v;
  }
  Real eval_abs(Real s) const {
    Real v = 0;
    for (size_t k = abs_coeffs_.size(); k-- > 0;) v = v * std::abs(s) + abs_coeffs_[k];
    return v;
  }
  /// Golden-section search of |f| on [a, b]; true when its minimum is below 1e-6 of the
  /// magnitude of F's terms there.
  bool near_zero_minimum(Real a, Real b) const {
    const Real g = (std::sqrt(5.0L) - 1) / 2;
    Real x1 = b - g * (b - a), x2 = a + g * (b - a);
    Real f1 = std::abs(eval(x1)), f2 = std::abs(eval(x2));
    for (int k = 0; k < 80; ++k) {
      if (f1 < f2) {
        b = x2;
        x2 = x1;
        f2 = f1;
        x1 = b - g * (b - a);
        f1 = std::abs(eval(x1));
      } else {
        a = x1;
        x1 = x2;
        f1 = f2;
        x2 = a + g * (b - a);
        f2 = std::abs(eval(x2));
      }
    }
    const Real x = 0.5L * (a + b);
    return std::abs(eval(x)) < 1e-6L * eval_abs(x);
  }

  std::vector<Monomial> terms_;
  int degree_;
  std::vector<Real> coeffs_, abs_coeffs_;
};

/// A random direction, uniform on the sphere.
Vec3 random_unit(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  Vec3 v;
  do v = Vec3(u(rng), u(rng), u(rng));
  while (v.squaredNorm() > 1 || v.squaredNorm() < 1e-6);
  return v.normalized();
}

/// A random camera for the row tests: the eye 2.5 to 4.5 scene radii from the centre, looking
/// near it, `size` × `size` rays.
View random_view(const Vec3& centre, double radius, int size, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  View view;
  view.eye = centre + radius * (2.5 + 2 * std::abs(u(rng))) * random_unit(rng);
  view.target = centre + 0.2 * radius * random_unit(rng);
  view.forward = (view.target - view.eye).normalized();
  view.right = view.forward.cross(random_unit(rng)).normalized();
  view.up = view.right.cross(view.forward);
  view.tan_half_fov = 1.1 * radius / (view.target - view.eye).norm();
  view.width = view.height = size;
  return view;
}

}  // namespace zeroset::test
