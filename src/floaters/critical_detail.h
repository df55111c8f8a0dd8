#pragma once
// Newton's method towards points where ∇F = 0 (Rösch et al. §3.3: the β estimator's corrector
// r with F_xx r = F_x), shared by the floaters and the metrics. Private to the floaters module.
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <optional>

#include "zeroset/types.h"

namespace zeroset::detail {

/// The corrector r solving F_xx r = F_x (in the least squares sense over the Hessian's non-null
/// eigendirections when it has a null one), and the Hessian's extreme |eigenvalues|. `reaches`
/// is false when ∇F has a component along a (numerically) null
/// direction of the Hessian: ∇F cannot vanish ahead (a parabolic cylinder), r is meaningless.
struct Corrector {
  Vec3 step = Vec3::Zero();
  bool reaches = false;
  double smallest = 0;  // smallest |eigenvalue|
  double largest = 0;   // largest |eigenvalue|
};

inline Corrector newton_corrector(const Vec3& gradient, const Mat3& hessian) {
  Corrector c;
  const double gnorm = gradient.norm();
  if (!std::isfinite(gnorm) || !hessian.allFinite()) return c;
  Eigen::SelfAdjointEigenSolver<Mat3> es;
  es.computeDirect(hessian, Eigen::EigenvaluesOnly);
  c.largest = es.eigenvalues().cwiseAbs().maxCoeff();
  c.smallest = es.eigenvalues().cwiseAbs().minCoeff();
  if (gnorm == 0) {
    c.reaches = true;
    return c;
  }
  if (!(c.largest > 0)) return c;  // F is linear here: no critical point ahead
  if (c.smallest > 1e-6 * c.largest) {
    // No null direction: r = F_xx⁻¹ F_x. The 3×3 inverse by cofactors is accurate to about
    // cond·ε ≤ 1e-10 here, and much cheaper than the eigenvectors the general case needs.
    c.step = hessian.inverse() * gradient;
    c.reaches = c.step.allFinite();
    return c;
  }
  es.computeDirect(hessian);
  const Vec3 lambda = es.eigenvalues();
  for (int k = 0; k < 3; ++k) {
    const Vec3 v = es.eigenvectors().col(k);
    const double comp = v.dot(gradient);
    // The closed-form 3×3 solver is accurate to about 1e-8 relative for repeated eigenvalues,
    // so anything below 1e-6 of the largest counts as a null direction.
    if (std::abs(lambda[k]) > 1e-6 * c.largest)
      c.step += (comp / lambda[k]) * v;
    else if (std::abs(comp) > 1e-6 * gnorm)
      return c;  // ∇F changes nowhere along this direction, yet has a component in it
  }
  c.reaches = true;
  return c;
}

/// F_xx⁻¹ F_x when a cheap bound shows F_xx far from singular: |det F_xx| > 2e-6 ‖F_xx‖_F³, so
/// every |eigenvalue| exceeds 2e-6 of the largest (the smallest is |det| over the product of the
/// other two, each at most ‖F_xx‖_F). newton_corrector() then takes the same step; this skips
/// its eigenvalues. Empty when the bound fails or anything is not finite.
inline std::optional<Vec3> regular_corrector(const Vec3& gradient, const Mat3& hessian) {
  const double size = hessian.norm();
  if (!std::isfinite(size) || !gradient.allFinite() ||
      !(std::abs(hessian.determinant()) > 2e-6 * size * size * size))
    return std::nullopt;
  const Vec3 step = hessian.inverse() * gradient;
  if (!step.allFinite()) return std::nullopt;
  return step;
}

}  // namespace zeroset::detail
