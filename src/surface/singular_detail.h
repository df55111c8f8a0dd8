#pragma once
// Private to the singular-set search: Newton correctors onto S = {F = 0, ∇F = 0}, the shape of
// the Hessian there, and curve tracing. See docs/singular.md.
#include <Eigen/Eigenvalues>
#include <vector>

#include "zeroset/detail/segment.h"
#include "zeroset/expr/field.h"
#include "zeroset/surface/analysis.h"
#include "zeroset/surface/clip.h"
#include "zeroset/surface/singular_set.h"
#include "zeroset/types.h"

namespace zeroset::detail {

// Sizes that make the tests scale-free: the grid cell, the scene radius, and typical |∇F| and
// ‖H‖ near the surface (medians over grid points within a cell of F = 0).
struct SingularScales {
  double radius = 1;
  double cell = 1;
  double grad = 1;
  double hess = 1;
  // |∇F| and |F| below these count as zero at a converged point.
  double grad_tolerance() const { return 1e-9 * grad; }
  double value_tolerance() const { return 1e-9 * grad * cell; }
};

struct Converged {
  Vec3 p = Vec3::Zero();
  bool ok = false;
  bool ran_off = false;  // stopped for going beyond max_move
};

/// One Gauss–Newton step towards the singular set from F, ∇F and ∇²F at a point: the
/// minimum-norm least-squares solution of J x = r, r = (F/h, ∇F), J = [∇Fᵀ/h; ∇²F], in the
/// coordinates given by the columns of `basis` (3×N), returned in space (the point moves by
/// minus it). None where J vanishes. `damped`: a Levenberg–Marquardt step instead, μ = ‖J‖ ‖r‖ / h
/// added to JᵀJ's diagonal (Fan and Yuan's choice of μ, proportional to the residual, keeps
/// the convergence superlinear onto a curve of solutions). Far from S, where the Hessian's
/// weak directions are not yet the curve's, the plain step runs along the curve instead of
/// onto it: sheets meeting at 40° with other factors varying near them sent every grid node
/// four cells along their double line and none onto it.
template <int N>
std::optional<Vec3> singular_gauss_newton_step(double f, const Vec3& g, const Mat3& hessian,
                                               const Eigen::Matrix<double, 3, N>& basis,
                                               double h, bool damped = false) {
  Eigen::Matrix<double, 4, 3> j;
  j.row(0) = g.transpose() / h;
  j.bottomRows<3>() = hessian;
  Eigen::Vector4d r;
  r << f / h, g;
  const Eigen::Matrix<double, 4, N> jb = j * basis;
  Eigen::Matrix<double, N, N> gram = jb.transpose() * jb;
  if (damped) gram.diagonal().array() += j.norm() * r.norm() / h;
  const auto x = min_norm_solve<N>(gram, jb.transpose() * r, Spectrum::kGram, 1e-24, true);
  if (!x) return std::nullopt;
  return Vec3(basis * *x);
}

// Levenberg–Marquardt on (F/h, ∇F) = 0 from `start` with minimum-norm least-squares steps
// (the system is rank deficient on curves of S). ok when it converges inside `max_move` of
// `start` to a point where F and ∇F vanish (SingularScales' tolerances).
Converged converge_to_singular(Evaluator& ev, const Vec3& start, const SingularScales& s,
                               double max_move);

// The same, with the steps restricted to the plane through `start` normal to `t` (unit): finds
// where a curve of S crosses that plane. ok also requires the point to stay within `max_move`.
Converged converge_in_plane(Evaluator& ev, const Vec3& start, const Vec3& t,
                            const SingularScales& s, double max_move);

// The Hessian's eigen decomposition sorted by |eigenvalue|, largest first.
struct HessianShape {
  Vec3 abs_eigenvalues = Vec3::Zero();  // descending
  Mat3 vectors = Mat3::Identity();      // column k belongs to abs_eigenvalues[k]
  // Eigenvalues at most `fraction` of max(largest, scale) count as zero.
  int nullity(double scale, double fraction = 1e-6) const;
};
HessianShape hessian_shape(const Mat3& h);

// Whether H's second eigenvalue is zero but for rounding (at most 1e-4 of the first): all along
// a cuspidal edge, or right at a pinch or triple point.
bool rank_one_hessian(const Mat3& h, double hess_scale);

// The direction of the curve of S at a point with Hessian h: its null vector, oriented along
// `previous`. Where two or three eigenvalues are small (pinch and triple points), the projection
// of `previous` onto their span; where the second is zero but for rounding (a cuspidal edge),
// the projection of `chord`, the step just taken. Zero when there is no direction.
Vec3 curve_tangent(const Mat3& h, const Vec3& previous, const Vec3& chord, double hess_scale);

// det Q / ‖Q‖² for Q = H restricted to the plane normal to t: < 0 crossing, > 0 isolated,
// near 0 where Q has rank one (split_by_kind decides how near); 0 when Q vanishes.
double normal_form_det(const Mat3& h, const Vec3& t, double hess_scale);

// A unit basis of the plane normal to the unit vector t.
void normal_basis(const Vec3& t, Vec3& u, Vec3& v);

enum class WalkEnd { kClip, kClosed, kStalled, kBudget, kMetItself };

// Follows the curve of S from `start` (on it) along `t`, one vertex every `spacing`, until it
// leaves the clip (the last vertex then lies on the clip within 1e-13 of the scene radius), closes
// on `start`, comes back to one of its own vertices (through a triple point onto a loop that
// misses `start`: the last vertex is then a copy of that one), stalls or uses up `budget`
// vertices (decremented). Returns the vertices after start.
std::vector<Vec3> walk_curve(Evaluator& ev, const Clip& clip, const Vec3& start, Vec3 t,
                             const SingularScales& s, double spacing, int& budget, WalkEnd& end);

// Triple points on a curve: where three or more sheets meet, F vanishes to third order and
// so does H; the vertices where ‖H‖ has a small local minimum, refined by golden-section search
// on the curve, that reach ‖H‖ = 0.
std::vector<Vec3> triple_points_on(Evaluator& ev, const SingularCurve& curve,
                                   const SingularScales& s, double spacing);

// Splits a curve into pieces of one kind each: at pinch points (where det Q changes sign,
// located by bisection and appended to `pinches`) and around stretches where Q has rank one
// (cuspidal edges: degenerate pieces, with no pinch points in them).
std::vector<SingularCurve> split_by_kind(Evaluator& ev, const SingularCurve& curve,
                                         const SingularScales& s, std::vector<Vec3>& pinches);

}  // namespace zeroset::detail
