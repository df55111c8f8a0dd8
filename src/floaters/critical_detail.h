#pragma once
// Newton's method towards points where ∇F = 0 (Rösch et al. §3.3: the β estimator's corrector
// r with F_xx r = F_x), shared by the floaters and the metrics. Private to the floaters module.
#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <optional>

#include "zeroset/types.h"

namespace zeroset::detail {

/// The Hessian's eigen decomposition with the corrector r solving F_xx r = F_x in the least
/// squares sense. `reaches` is false when ∇F has a component along a (numerically) null
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
  es.computeDirect(hessian);
  const Vec3 lambda = es.eigenvalues();
  c.largest = lambda.cwiseAbs().maxCoeff();
  c.smallest = lambda.cwiseAbs().minCoeff();
  if (gnorm == 0) {
    c.reaches = true;
    return c;
  }
  if (!(c.largest > 0)) return c;  // F is linear here: no critical point ahead
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

}  // namespace zeroset::detail
