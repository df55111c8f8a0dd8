// The normals of hits: ∇F from the row's expansions where that is safe, else from F's own
// terms, and a fallback where ∇F vanishes.
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "raycast_detail.h"

namespace zeroset::detail {
namespace {

/// The derivatives of G at t·(base + s·step) along the ray (a), the row's step (b) and the
/// row's plane normal (c) (see row_gradient) from the ray's
/// polynomial f, the row's derivative in s and the row's ∇G·n, and the derivative of the
/// rounding band at x (e); unrolled when D > 0.
template <int D>
void row_derivatives(const double* f, const double* row_ds, const double* normal_row,
                     const double* band_coeffs, int d_, double s, double t, double x,
                     double* abce) {
  const int d = D > 0 ? D : d_;
  double a = 0, b = 0, c = 0, e = 0;
  for (int k = d; k >= 1; --k) {
    a = std::fma(a, t, k * f[k]);
    e = std::fma(e, x, k * band_coeffs[k]);
    const double* r = row_ds + k * (k - 1) / 2;
    double v = r[k - 1];
    for (int j = k - 2; j >= 0; --j) v = std::fma(v, s, r[j]);
    b = std::fma(b, t, v);
  }
  for (int k = d - 1; k >= 0; --k) {
    const double* r = normal_row + k * (k + 1) / 2;
    double v = r[k];
    for (int j = k - 1; j >= 0; --j) v = std::fma(v, s, r[j]);
    c = std::fma(c, t, v);
  }
  abce[0] = a;
  abce[1] = b;
  abce[2] = c;
  abce[3] = e;
}

/// ∇F at the hit eye + t·(base + s·step) of the current ray from the row's expansions
/// (its coefficients must be in `coeffs`): the derivatives along the ray d = base + s·step,
/// along step and along n = base × step are polynomials in t whose coefficients are
/// polynomials in s, a few dozen multiply-adds instead of evaluating ∇F's terms. They are
/// those of G, translated to the eye, so they round on the scale of G's terms: `error`
/// receives a bound on the error of the result (scaled like it), from the derivative of the
/// rounding band. False for a row of one ray.
bool row_gradient(const RayCaster& rc, double s, double t, Vec3& g, double& error) {
  if (!rc.has_row_normals) return false;
  // Fused multiply-adds in the order complete4 uses, so that both give the same bits.
  const double dx = std::fma(s, rc.step.x(), rc.base.x()),
               dy = std::fma(s, rc.step.y(), rc.base.y()),
               dz = std::fma(s, rc.step.z(), rc.base.z());
  const double x = t * std::max({std::abs(dx), std::abs(dy), std::abs(dz)});
  // a = ∇G·d = f'(t); b = ∇G·step = Σ_k t^(k−1) ∂G_k/∂s; c = ∇G·n = Σ_k t^k (∇G·n)_k;
  // e: the derivative of the rounding band.
  double abce[4];
  const double *f = rc.ray_coeffs, *ds_row = rc.row_ds.data(), *h = rc.normal_row.data(),
               *bc = rc.band_coeffs.data();
  switch (rc.degree) {
    case 1:
      row_derivatives<1>(f, ds_row, h, bc, rc.degree, s, t, x, abce);
      break;
    case 2:
      row_derivatives<2>(f, ds_row, h, bc, rc.degree, s, t, x, abce);
      break;
    case 3:
      row_derivatives<3>(f, ds_row, h, bc, rc.degree, s, t, x, abce);
      break;
    case 4:
      row_derivatives<4>(f, ds_row, h, bc, rc.degree, s, t, x, abce);
      break;
    case 5:
      row_derivatives<5>(f, ds_row, h, bc, rc.degree, s, t, x, abce);
      break;
    case 6:
      row_derivatives<6>(f, ds_row, h, bc, rc.degree, s, t, x, abce);
      break;
    default:
      row_derivatives<0>(f, ds_row, h, bc, rc.degree, s, t, x, abce);
      break;
  }
  const double a = abce[0], b = abce[1], c = abce[2];
  // With the dual basis of (d, step, n): ∇ = [a (|step|² d − (d·step) step)
  // + b (|d|² step − (d·step) d) + c n] / |n|², |n|² = |d|²|step|² − (d·step)².
  // Plain scalars: Eigen's 3-vector expressions cost several times as much here.
  const double dd = squared_norm(dx, dy, dz), ds = std::fma(s, rc.row_ss, rc.row_dot);
  const double p = std::fma(a, rc.row_ss, -(b * ds)) * rc.row_inverse_nn,
               q = std::fma(b, dd, -(a * ds)) * rc.row_inverse_nn, r = c * rc.row_inverse_nn;
  g = Vec3(std::fma(r, rc.row_normal.x(), std::fma(q, rc.step.x(), p * dx)),
           std::fma(r, rc.row_normal.y(), std::fma(q, rc.step.y(), p * dy)),
           std::fma(r, rc.row_normal.z(), std::fma(q, rc.step.z(), p * dz)));
  // Each directional derivative along a unit vector rounds by at most the derivative of the
  // band; the dual basis of the row's (well-conditioned) basis scales that by about
  // |d|²|step|² / |n|², which a factor 4 covers.
  error = 4 * abce[3] * dd * rc.row_ss * rc.row_inverse_nn;
  return true;
}

/// A bound on the magnitude of the terms of ∇F at p: Σ_k gradient_bound[k] max|p_i|^k.
double gradient_scale(const RayCaster& rc, const Vec3& p) {
  const double m = p.cwiseAbs().maxCoeff();
  double bound = 0;
  for (size_t k = rc.gradient_bound.size(); k-- > 0;)
    bound = std::fma(bound, m, rc.gradient_bound[k]);
  return bound;
}

/// ∇F at p from F's own terms (well conditioned near the surface, unlike the translated
/// form).
void gradient(RayCaster& rc, const Vec3& p, Vec3& g) {
  double* mono = rc.powers.data();
  rc.derivative_monomials.evaluate(p, mono);
  sparse_gradient(rc.derivative, mono, g.data());
}

/// Where ∇F = 0 (a node, or every point of a squared surface such as (x²+y²+z²−1)²): the
/// Hessian's principal eigenvector is the normal of the underlying smooth sheet when F is
/// a square; otherwise face the viewer.
Vec3 fallback_normal(RayCaster& rc, const Vec3& p, const Vec3& dir) {
  const FieldSample s = rc.evaluator.sample(p, Derivatives::kHessian);
  if (s.hessian.allFinite() && s.hessian.norm() > 0) {
    Eigen::SelfAdjointEigenSolver<Mat3> eig(s.hessian);
    const Eigen::Vector3d ev = eig.eigenvalues().cwiseAbs();
    int best = 0;
    ev.maxCoeff(&best);
    const double second = (ev.sum() - ev[best]);
    // Only a clearly dominant direction is a sheet's normal (rank one, as for F = g²).
    if (ev[best] > 4 * second) return eig.eigenvectors().col(best);
  }
  return -dir;
}

}  // namespace

void complete(RayCaster& rc, double s, double t, int side, SurfaceHit& hit) {
  const Vec3 dir = rc.parallel ? rc.base
                               : Vec3(std::fma(s, rc.step.x(), rc.base.x()),
                                      std::fma(s, rc.step.y(), rc.base.y()),
                                      std::fma(s, rc.step.z(), rc.base.z()));
  const double dx = dir.x(), dy = dir.y(), dz = dir.z();
  const Vec3 origin = ray_origin(rc, s);
  hit.t = t;
  hit.point =
      Vec3(std::fma(t, dx, origin.x()), std::fma(t, dy, origin.y()), std::fma(t, dz, origin.z()));
  Vec3 g;
  if (rc.exact) {
    // ∇F lost to cancellation (a node, or a squared surface where ∇F = 2g∇g is tiny at the
    // root) has a meaningless direction: treat it as vanishing.
    const double floor = kRelativeGradientFloor * gradient_scale(rc, hit.point);
    // The row's expansions give ∇F cheaply; it is used where it is far from vanishing and
    // far above the bound on its own rounding (a relative error below 1e-3 in that worst
    // case, below 1e-9 in practice) and the decision below is the same. Elsewhere
    // (near nodes, on squared surfaces, for single rays) ∇F comes from F's own terms.
    double error = 0;
    if (row_gradient(rc, s, t, g, error) &&
        in_open_range(
            squared_norm(g.x(), g.y(), g.z()),
            std::max(square(kRowGradientMargin * floor), square(kRowGradientAccuracy * error)))) {
      hit.singular = false;
    } else {
      gradient(rc, hit.point, g);
      hit.singular = !(g.allFinite() && g.squaredNorm() > floor * floor);
    }
  } else {
    rc.evaluator.value_gradient(hit.point, g);
    hit.singular = !(g.allFinite() && g.squaredNorm() > 0);
  }
  if (hit.singular) g = fallback_normal(rc, hit.point, dir);
  // Which side the eye is on: the sign F has along the ray before the hit, or, for a hit
  // at the clip entry, the gradient's direction.
  const double gd = std::fma(g.z(), dz, std::fma(g.y(), dy, g.x() * dx));
  hit.front = side != 0 ? side > 0 : gd < 0;
  const double k = (gd > 0 ? -1 : 1) / std::sqrt(squared_norm(g.x(), g.y(), g.z()));
  hit.normal = Vec3(k * g.x(), k * g.y(), k * g.z());
}

}  // namespace zeroset::detail
