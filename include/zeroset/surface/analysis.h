#pragma once
/// The local geometry of F: the residual |F|/|∇F|, Newton's method onto F = 0 and onto the
/// curve F = 0 ∩ ∂clip, the Newton step towards ∇F = 0 (the distance to a singular point) and
/// the search for singular points. The floaters, the mesher and the metrics all use these.
///
/// Header only: every function is compiled into its caller, as part of the caller's module.
/// The modules are built with different floating-point settings (the floaters without
/// contraction into fused multiply-adds, the mesher with it, both for this processor, whose
/// fused multiply-add Eigen uses), and each module's results depend on its own rounding, so no
/// module may link another's out-of-line copy: critical_step() and find_critical_point(),
/// which both modules use, are always inlined; the others are one-liners or have one module
/// as their only caller.
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <optional>

#include "zeroset/expr/field.h"
#include "zeroset/surface/clip.h"
#include "zeroset/types.h"

namespace zeroset {

// ---- residual and Newton's method onto F = 0 ------------------------------------------------

/// |F|/|∇F| (the first-order distance to F = 0) without infinities: 0 on the surface, the
/// largest double where it is undefined (∇F = 0 with F ≠ 0, or anything not finite).
inline double residual(double value, double gradient_norm) {
  if (value == 0) return 0;
  if (!std::isfinite(value) || !std::isfinite(gradient_norm))
    return std::numeric_limits<double>::max();
  const double r = std::abs(value) / gradient_norm;
  return std::isfinite(r) ? r : std::numeric_limits<double>::max();
}

/// Whether |F|/|∇F| means something at a point: ∇F ≠ 0 and F and ∇F finite.
inline bool has_residual(double value, double gradient_norm) {
  return gradient_norm > 0 && std::isfinite(gradient_norm) && std::isfinite(value);
}

/// One Newton step onto F = 0 from a point with F = value and ∇F = gradient:
/// −(F/|∇F|²) ∇F. Not finite where ∇F = 0: callers check.
inline Vec3 surface_newton_step(double value, const Vec3& gradient) {
  return -(value / gradient.squaredNorm()) * gradient;
}

/// Newton's method onto F = 0 from p (at most 40 steps). True when it reaches |F|/|∇F| <
/// `tolerance` within `max_move` of where it started; p is then the point reached. False when
/// it does not converge, wanders farther, or meets ∇F = 0 (true there only if F = 0).
inline bool project_onto_surface(Evaluator& ev, Vec3& p, double tolerance, double max_move) {
  const Vec3 start = p;
  for (int it = 0; it < 40; ++it) {
    Vec3 g;
    const double f = ev.value_gradient(p, g);
    const double g2 = g.squaredNorm();
    if (!std::isfinite(f) || !(g2 > 0) || !std::isfinite(g2)) return f == 0;
    if (std::abs(f) / std::sqrt(g2) < tolerance) return (p - start).norm() <= max_move;
    p += surface_newton_step(f, g);
    if ((p - start).norm() > max_move) return false;
  }
  return false;
}

// ---- Newton's method onto the curve F = 0 ∩ ∂clip ---------------------------------------------

/// Moves p onto the clip surface G = 0 along ∇G (at most four Newton steps: exact for spheres
/// and planes).
inline Vec3 snap_to_clip(const Clip& clip, Vec3 p) {
  for (int it = 0; it < 4; ++it) {
    Vec3 grad;
    const double g = clip.value_gradient(p, grad);
    const double n2 = grad.squaredNorm();
    if (!std::isfinite(g) || n2 == 0) break;
    if (g == 0) break;
    p -= (g / n2) * grad;
  }
  return p;
}

/// Newton's method on (F, G) = 0 from p with minimum-norm steps (x −= Jᵀ(JJᵀ)⁻¹(F, G), J the
/// rows ∇F and ∇G, regularised where ∇F ∥ ∇G), until the step stops shrinking, then
/// snap_to_clip. When it wanders farther than `max_move` from p, meets a non-finite F or
/// cannot solve, it gives up and only snaps p onto G = 0. Converges to the curve: for meshes,
/// whose boundary vertices must lie on both surfaces.
inline Vec3 project_onto_clip_curve(Evaluator& ev, const Clip& clip, const Vec3& p,
                                    double max_move) {
  Vec3 x = p;
  for (int it = 0; it < 40; ++it) {
    Vec3 gf, gg;
    const double f = ev.value_gradient(x, gf);
    const double g = clip.value_gradient(x, gg);
    if (!std::isfinite(f) || !gf.allFinite()) return snap_to_clip(clip, p);
    double a = gf.dot(gf), b = gf.dot(gg), d = gg.dot(gg);
    const double reg = 1e-12 * (a + d);
    a += reg, d += reg;
    const double det = a * d - b * b;
    if (!(det > 0)) return snap_to_clip(clip, p);
    const double l0 = (d * f - b * g) / det, l1 = (a * g - b * f) / det;
    const Vec3 step = l0 * gf + l1 * gg;
    x -= step;
    if ((x - p).norm() > max_move || !x.allFinite()) return snap_to_clip(clip, p);
    if (step.norm() <= 1e-15 * (1 + x.norm())) break;
  }
  return snap_to_clip(clip, x);
}

/// A bounded move towards the curve for a point on the clip boundary (already put there by
/// Clip::project): `steps` Newton steps on F along the boundary (in the direction of ∇F
/// projected onto the boundary's tangent plane), each at most `max_step` long and followed by
/// Clip::project. Unlike project_onto_clip_curve() it never jumps farther than the caller
/// allows and needs no convergence: for particles that move a little every step and settle on
/// the curve over several steps.
inline Vec3 step_onto_clip_curve(Evaluator& ev, const Clip& clip, Vec3 p, double max_step,
                                 int steps = 2) {
  for (int it = 0; it < steps; ++it) {
    Vec3 g, ng;
    const double f = ev.value_gradient(p, g);
    clip.value_gradient(p, ng);
    const Vec3 t = g - g.dot(ng) * ng;
    const double t2 = t.squaredNorm();
    if (!std::isfinite(f) || !(t2 > 0) || !std::isfinite(t2)) break;
    Vec3 step = -(f / t2) * t;
    const double len = step.norm();
    if (len > max_step) step *= max_step / len;
    p = clip.project(p + step);
  }
  return p;
}

// ---- the Newton step towards ∇F = 0 and singular points -------------------------------------

/// The Newton step r towards a point where ∇F = 0 (Rösch et al. §3.3: the β estimator's
/// corrector, F_xx r = F_x), and the Hessian's extreme |eigenvalues|.
struct CriticalStep {
  /// F_xx⁻¹ F_x; where the Hessian has (numerically) null eigendirections, the least-squares
  /// solution over the others (a pseudo-inverse). Zero when nothing is finite or F_xx = 0.
  Vec3 step = Vec3::Zero();
  /// False when ∇F has a component along a null direction of the Hessian (∇F cannot vanish
  /// ahead: a parabolic cylinder; `step` then only says where the other directions lead), or
  /// F_xx = 0 (F is linear here), or anything is not finite.
  bool reaches = false;
  double smallest = 0;  ///< smallest |eigenvalue| of F_xx
  double largest = 0;   ///< largest |eigenvalue| of F_xx
};

/// The CriticalStep at a point with gradient F_x and Hessian F_xx. An eigenvalue counts as
/// null below 1e-6 of the largest (the closed-form 3×3 eigensolver is accurate to about 1e-8
/// relative for repeated eigenvalues).
[[gnu::always_inline]] inline CriticalStep critical_step(const Vec3& gradient,
                                                         const Mat3& hessian) {
  CriticalStep c;
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
  bool reaches = true;
  for (int k = 0; k < 3; ++k) {
    const Vec3 v = es.eigenvectors().col(k);
    const double comp = v.dot(gradient);
    if (std::abs(lambda[k]) > 1e-6 * c.largest)
      c.step += (comp / lambda[k]) * v;
    else if (std::abs(comp) > 1e-6 * gnorm)
      reaches = false;  // ∇F changes nowhere along this direction, yet has a component in it
  }
  c.reaches = reaches;
  return c;
}

/// F_xx⁻¹ F_x when a cheap bound shows F_xx far from singular: |det F_xx| > 2e-6 ‖F_xx‖_F³, so
/// every |eigenvalue| exceeds 2e-6 of the largest (the smallest is |det| over the product of
/// the other two, each at most ‖F_xx‖_F). critical_step() then takes the same step; this skips
/// its eigenvalues. Empty when the bound fails or anything is not finite.
inline std::optional<Vec3> regular_critical_step(const Vec3& gradient, const Mat3& hessian) {
  const double size = hessian.norm();
  if (!std::isfinite(size) || !gradient.allFinite() ||
      !(std::abs(hessian.determinant()) > 2e-6 * size * size * size))
    return std::nullopt;
  const Vec3 step = hessian.inverse() * gradient;
  if (!step.allFinite()) return std::nullopt;
  return step;
}

/// Estimated distance from p to the nearest point where ∇F = 0: the length of the Newton
/// corrector r with ∇²F(p) r = ∇F(p) (Rösch et al. §3.3, the β estimator; critical_step()),
/// the least-squares answer where the Hessian is singular, or +∞ when ∇F has a component along
/// a null direction (no critical point ahead, e.g. a parabolic cylinder). 0 where ∇F = 0.
inline double singular_distance(const Vec3& gradient, const Mat3& hessian) {
  if (gradient.squaredNorm() == 0) return 0;
  const CriticalStep c = critical_step(gradient, hessian);
  return c.reaches ? c.step.norm() : std::numeric_limits<double>::infinity();
}

/// Which eigenvalues of a symmetric matrix min_norm_solve() keeps: those of magnitude above
/// the cutoff (any symmetric matrix, e.g. a Hessian), or those above it with their sign (a Gram
/// matrix JᵀJ, positive semidefinite, whose rounding may leave tiny negative eigenvalues that
/// must not be inverted).
enum class Spectrum { kSymmetric, kGram };

/// The minimum-norm least-squares solution x = A⁺b of a symmetric N×N system, from A's
/// eigendecomposition: components along eigenvectors whose eigenvalue is at most
/// `cutoff`·max|λ| (see Spectrum) are left out. `closed_form`: Eigen's closed-form 2×2/3×3
/// eigensolver (computeDirect), else the iterative one; each caller keeps the one its results
/// were measured with. None when A is zero or not finite. The one home of this solve: the
/// improver's and the singular-set search's Newton steps use it.
template <int N>
std::optional<Eigen::Matrix<double, N, 1>> min_norm_solve(const Eigen::Matrix<double, N, N>& a,
                                                          const Eigen::Matrix<double, N, 1>& b,
                                                          Spectrum spectrum, double cutoff,
                                                          bool closed_form) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es;
  if constexpr (N == 2 || N == 3) {
    if (closed_form)
      es.computeDirect(a);
    else
      es.compute(a);
  } else {
    es.compute(a);
  }
  const auto& lambda = es.eigenvalues();
  const double top = lambda.cwiseAbs().maxCoeff();
  if (!(top > 0) || !std::isfinite(top)) return std::nullopt;
  Eigen::Matrix<double, N, 1> x = Eigen::Matrix<double, N, 1>::Zero();
  for (int k = 0; k < N; ++k) {
    const double l = spectrum == Spectrum::kGram ? lambda[k] : std::abs(lambda[k]);
    if (l > cutoff * top)
      x += (es.eigenvectors().col(k).dot(b) / lambda[k]) * es.eigenvectors().col(k);
  }
  return x;
}

/// The improver's step towards ∇F = 0: the least-squares solution of F_xx r = F_x over the
/// eigendirections with |λ| > 1e-9 of the largest (the full iterative eigensolver), whether or
/// not ∇F has a component along the others, so a singular Hessian gives a long, not an
/// infinite, step, and Newton's method with it converges onto singular curves too. Infinite
/// where F_xx = 0 (no critical point in sight) or anything is not finite. critical_step()
/// decides more (reachability, conditioning) and is cheaper away from singular points; the
/// mesher's results depend on this one's rounding, so both stay.
inline Vec3 pseudo_inverse_step(const Vec3& gradient, const Mat3& hessian) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!hessian.allFinite() || !gradient.allFinite()) return Vec3::Constant(kInf);
  return min_norm_solve<3>(hessian, gradient, Spectrum::kSymmetric, 1e-9, false)
      .value_or(Vec3::Constant(kInf));
}

/// How find_critical_point() searches.
struct CriticalSearch {
  int iterations = 12;  ///< Newton steps at most
  /// Gives up when an iterate lies farther than this from the start.
  double reach = std::numeric_limits<double>::infinity();
  /// > 0: nodes only. Every iterate's Hessian must have smallest/largest |eigenvalue| above
  /// this and a critical_step() that reaches; converged when the next step would be at most
  /// `tolerance`·(|x| + `length`), at x. 0: any critical point, singular curves too, by
  /// pseudo_inverse_step(); converged once a step taken was at most that long.
  double min_conditioning = 0;
  double tolerance = 1e-14;
  double length = 1;
};

/// A point where ∇F = 0, with F and ∇F there (judging whether it lies on F = 0 is the caller's:
/// F's scale differs between uses) and, for nodes, the Hessian's largest |eigenvalue|.
struct CriticalPoint {
  Vec3 point;
  double value = 0;
  Vec3 gradient = Vec3::Zero();
  double largest = 0;
};

/// Newton's method on ∇F = 0 from `start`. Empty when it does not converge within `search`
/// (or a step is not finite). Always inlined: the floaters and the mesher are built with
/// different floating-point contraction, and each keeps its own rounding.
[[gnu::always_inline]] inline std::optional<CriticalPoint> find_critical_point(
    Evaluator& ev, const Vec3& start, const CriticalSearch& search) {
  Vec3 q = start;
  for (int it = 0; it < search.iterations; ++it) {
    const FieldSample fs = ev.sample(q, Derivatives::kHessian);
    if (search.min_conditioning > 0) {
      const CriticalStep c = critical_step(fs.gradient, fs.hessian);
      if (!c.reaches || !(c.smallest > search.min_conditioning * c.largest)) return std::nullopt;
      if (c.step.squaredNorm() == 0 ||
          c.step.norm() <= search.tolerance * (q.norm() + search.length))
        return CriticalPoint{q, fs.value, fs.gradient, c.largest};
      q -= c.step;
      if (!q.allFinite() || (q - start).norm() > search.reach) return std::nullopt;
    } else {
      const Vec3 d = pseudo_inverse_step(fs.gradient, fs.hessian);
      if (!d.allFinite()) return std::nullopt;
      q -= d;
      if ((q - start).norm() > search.reach) return std::nullopt;
      if (d.norm() <= search.tolerance * (search.length + q.norm())) {
        CriticalPoint found{q, 0, Vec3::Zero(), 0};
        found.value = ev.value_gradient(q, found.gradient);
        return found;
      }
    }
  }
  return std::nullopt;
}

}  // namespace zeroset
