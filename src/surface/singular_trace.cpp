// Newton correctors onto the singular set and the predictor–corrector walk along its curves.
#include <algorithm>
#include <cmath>
#include <limits>

#include "singular_detail.h"

namespace zeroset::detail {
namespace {

constexpr int kNewtonIterations = 60;

// A second eigenvalue of H at most this fraction of the first is zero but for rounding: all
// along a cuspidal edge (its measured size there is rounding, up to about 1e-8), or right at a
// pinch or triple point.
constexpr double kRankOneHessian = 1e-4;

// Steps smaller than this (relative to the scene radius) end a Newton iteration.
constexpr double kStepTolerance = 1e-15;

// The minimum-norm least-squares solution of (JᵀJ) x = b for symmetric positive semidefinite
// A = JᵀJ: directions whose eigenvalue is below 1e-24 of the largest (singular values of J
// below 1e-12 of its largest) are left out.
bool is_singular_here(Evaluator& ev, const Vec3& p, const SingularScales& s) {
  Vec3 g;
  const double f = ev.value_gradient(p, g);
  return std::isfinite(f) && g.allFinite() && std::abs(f) <= s.value_tolerance() &&
         g.norm() <= s.grad_tolerance();
}

// One Gauss–Newton iteration at p (singular_gauss_newton_step), or NaN when F is undefined.
template <int N>
Vec3 gauss_newton_step(Evaluator& ev, const Vec3& p, const Eigen::Matrix<double, 3, N>& basis,
                       double h, bool damped) {
  const FieldSample fs = ev.sample(p, Derivatives::kHessian);
  if (!std::isfinite(fs.value) || !fs.gradient.allFinite() || !fs.hessian.allFinite())
    return Vec3::Constant(std::numeric_limits<double>::quiet_NaN());
  return singular_gauss_newton_step<N>(fs.value, fs.gradient, fs.hessian, basis, h, damped)
      .value_or(Vec3::Zero());
}

template <int N>
Converged converge(Evaluator& ev, const Vec3& start, const Eigen::Matrix<double, 3, N>& basis,
                   const SingularScales& s, double max_move, bool damped) {
  Converged c;
  c.p = start;
  const double tiny = kStepTolerance * s.radius;
  for (int it = 0; it < kNewtonIterations; ++it) {
    const Vec3 step = gauss_newton_step<N>(ev, c.p, basis, s.cell, damped);
    if (!step.allFinite()) return c;
    c.p -= step;
    if ((c.p - start).norm() > max_move) {
      c.ran_off = true;
      return c;
    }
    if (step.norm() <= tiny) break;
  }
  c.ok = is_singular_here(ev, c.p, s);
  return c;
}

}  // namespace

Converged converge_to_singular(Evaluator& ev, const Vec3& start, const SingularScales& s,
                               double max_move) {
  // Plain Gauss–Newton first: it converges fastest, and onto a cuspidal edge (where ∇F grows
  // only quadratically across the curve) the damped steps do not reach the tolerances within
  // the iterations. Where it ran off (beyond max_move: along a curve instead of onto it), the
  // damped steps (singular_gauss_newton_step); not where it converged to a point that is not
  // singular (a sphere's centre), where they would only take all their iterations to get
  // there too (a sphere's search took three times as long).
  const Converged plain = converge<3>(ev, start, Mat3::Identity(), s, max_move, false);
  if (plain.ok) return plain;
  if (plain.ok || !plain.ran_off) return plain;
  return converge<3>(ev, start, Mat3::Identity(), s, max_move, true);
}

Converged converge_in_plane(Evaluator& ev, const Vec3& start, const Vec3& t,
                            const SingularScales& s, double max_move) {
  Vec3 u, v;
  normal_basis(t, u, v);
  Eigen::Matrix<double, 3, 2> b;
  b.col(0) = u;
  b.col(1) = v;
  return converge<2>(ev, start, b, s, max_move, false);
}

int HessianShape::nullity(double scale, double fraction) const {
  const double ref = std::max(abs_eigenvalues[0], scale);
  int n = 0;
  for (int k = 0; k < 3; ++k) n += abs_eigenvalues[k] <= fraction * ref;
  return n;
}

HessianShape hessian_shape(const Mat3& h) {
  HessianShape out;
  if (!h.allFinite()) return out;
  Eigen::SelfAdjointEigenSolver<Mat3> es;
  es.computeDirect(h);
  std::array<int, 3> order{0, 1, 2};
  const Vec3 a = es.eigenvalues().cwiseAbs();
  std::sort(order.begin(), order.end(), [&](int i, int j) { return a[i] > a[j]; });
  for (int k = 0; k < 3; ++k) {
    out.abs_eigenvalues[k] = a[order[static_cast<size_t>(k)]];
    out.vectors.col(k) = es.eigenvectors().col(order[static_cast<size_t>(k)]);
  }
  return out;
}

bool rank_one_hessian(const Mat3& h, double hess_scale) {
  const HessianShape shape = hessian_shape(h);
  return shape.abs_eigenvalues[1] <=
         kRankOneHessian * std::max(shape.abs_eigenvalues[0], hess_scale);
}

Vec3 curve_tangent(const Mat3& h, const Vec3& previous, const Vec3& chord, double hess_scale) {
  const HessianShape shape = hessian_shape(h);
  const double ref = std::max(shape.abs_eigenvalues[0], hess_scale);
  // On the curve H t = 0 exactly (∇F = 0 all along it), so the null vector is the tangent as
  // long as the second eigenvalue stands clear of rounding: where sheets meet at 15°, it is
  // 2% of the first, and following the previous direction there instead drifted off the curve
  // (the walk stalled, and the curve came out in overlapping pieces). Only where it is as
  // small as rounding (at a pinch or triple point, or all along a cuspidal edge) are the
  // eigenvectors interchangeable: follow the previous direction within their span.
  const bool second_small = shape.abs_eigenvalues[1] <= 1e-4 * ref;
  const bool rank_one = shape.abs_eigenvalues[1] <= kRankOneHessian * ref;
  Vec3 t;
  if (!second_small) {
    t = shape.vectors.col(2);
  } else {
    const bool first_small = shape.abs_eigenvalues[0] <= 0.05 * hess_scale;
    if (first_small) return previous.normalized();  // H ≈ 0: no information, keep going
    const Vec3 n = shape.vectors.col(0);            // the one clearly non-null direction
    const Vec3 guide = rank_one ? chord : previous;
    t = guide - guide.dot(n) * n;
    if (t.norm() < 1e-3 * guide.norm()) t = shape.vectors.col(2);
  }
  const double len = t.norm();
  if (!(len > 0) || !std::isfinite(len)) return Vec3::Zero();
  t /= len;
  return previous.dot(t) < 0 ? Vec3(-t) : t;
}

void normal_basis(const Vec3& t, Vec3& u, Vec3& v) {
  const Vec3 a = std::abs(t.x()) < 0.6 ? Vec3::UnitX() : Vec3::UnitY();
  u = t.cross(a).normalized();
  v = t.cross(u).normalized();
}

double normal_form_det(const Mat3& h, const Vec3& t, double hess_scale) {
  Vec3 u, v;
  normal_basis(t, u, v);
  const double quu = u.dot(h * u), quv = u.dot(h * v), qvv = v.dot(h * v);
  const double norm2 = quu * quu + 2 * quv * quv + qvv * qvv;
  if (!(norm2 > 1e-16 * hess_scale * hess_scale)) return 0;
  return (quu * qvv - quv * quv) / norm2;
}

std::vector<Vec3> walk_curve(Evaluator& ev, const Clip& clip, const Vec3& start, Vec3 t,
                             const SingularScales& s, double spacing, int& budget, WalkEnd& end) {
  std::vector<Vec3> out;
  Vec3 p = start;
  double step = spacing;
  const double min_step = spacing / 512;
  const double cos_limit = std::cos(20.0 * 3.14159265358979323846 / 180);
  double walked = 0;
  bool on_rank_one = rank_one_hessian(ev.sample(start, Derivatives::kHessian).hessian, s.hess);
  for (;;) {
    if (budget <= 0) {
      end = WalkEnd::kBudget;
      return out;
    }
    const Vec3 q = p + step * t;
    const Converged c = converge_in_plane(ev, q, t, s, 0.5 * step);
    Vec3 next_t = Vec3::Zero();
    Mat3 h = Mat3::Zero();
    if (c.ok) {
      // On a cuspidal edge, where the previous direction would never turn with the curve, the
      // chord guides the new tangent (it has t's orientation: the correction is normal to t);
      // only where H has rank one at both ends, so a vertex that meets a pinch point, where
      // the chord carries the corrector's rounding across the curve, keeps to t as before.
      h = ev.sample(c.p, Derivatives::kHessian).hessian;
      next_t = curve_tangent(h, t, on_rank_one ? Vec3(c.p - p) : t, s.hess);
    }
    if (!c.ok || next_t.isZero() || next_t.dot(t) < cos_limit) {
      step *= 0.5;
      if (step < min_step) {
        end = WalkEnd::kStalled;
        return out;
      }
      continue;
    }
    if (!clip.is_empty_spec() && clip.value(c.p) > 0) {
      // Leaves the clip between p and c.p: bisect on the curve for the exit point.
      double lo = 0, hi = step;
      Vec3 inside = p;
      for (int it = 0; it < 80 && hi - lo > 1e-14 * s.radius; ++it) {
        const double mid = 0.5 * (lo + hi);
        const Converged m = converge_in_plane(ev, p + mid * t, t, s, 0.5 * step);
        if (!m.ok) break;
        if (clip.value(m.p) > 0) {
          hi = mid;
        } else {
          lo = mid;
          inside = m.p;
        }
      }
      if ((inside - p).norm() > 1e-3 * spacing) out.push_back(inside);
      --budget;
      end = WalkEnd::kClip;
      return out;
    }
    walked += (c.p - p).norm();
    if (walked > 2.5 * spacing && (c.p - start).norm() < 0.75 * spacing) {
      end = WalkEnd::kClosed;
      return out;
    }
    // Back at one of its own vertices (not the last few): it turned onto another curve at a
    // triple point and came round that curve's loop, and would go round forever. The walk
    // ends on that vertex, so the curves' graph has the loop and its junction.
    for (size_t k = 0; k + 3 < out.size(); ++k)
      if ((out[k] - c.p).norm() < 0.5 * spacing) {
        out.push_back(out[k]);
        end = WalkEnd::kMetItself;
        return out;
      }
    out.push_back(c.p);
    --budget;
    p = c.p;
    on_rank_one = rank_one_hessian(h, s.hess);
    if (next_t.dot(t) > std::cos(5.0 * 3.14159265358979323846 / 180))
      step = std::min(spacing, 1.5 * step);
    t = next_t;
  }
}

}  // namespace zeroset::detail
