// The special points on a traced curve of the singular set: triple points, where ‖H‖ vanishes,
// and the split of a curve by the form Q across it into crossing, isolated and degenerate
// pieces (pinch points where det Q changes sign). See docs/singular.md, "Classify the curves".
#include <algorithm>
#include <cmath>
#include <limits>

#include "singular_detail.h"

namespace zeroset::detail {
namespace {

// |det Q| / ‖Q‖² (about |λ₂ / λ₁|, Q's eigenvalues) at most this counts as Q of rank one. On a
// cuspidal edge (F ≈ u² − v³ across it) λ₂ is proportional to the offset v from the edge, and
// the corrector fixes v only to about the square root of the rounding of ∇F (which grows as
// v²): the ratio measured there is up to 1.3e-8 (docs/singular.md), with either sign. Away from
// a pinch point a crossing or isolated curve stays far above the tolerance; two sheets crossing
// at an angle a have a ratio of about (a/2)², so sheets closer than 0.1° count as a cusp.
constexpr double kRankOne = 1e-6;

// Outside the degenerate stretches a vertex has no sign, for the pinch points and a piece's
// kind, only where the ratio is below this (a triple point, or a vertex right at a pinch point).
constexpr double kNoSign = 1e-9;

}  // namespace

// Triple points on a curve: where three or more sheets meet, F vanishes to third order, so the
// Hessian vanishes too; along the curve ‖H‖ falls to zero there (a V-shaped minimum). Each
// vertex where ‖H‖ is a small local minimum is refined by golden-section search on ‖H‖ over the
// curve between its neighbours (points of the curve found in planes normal to that chord).
std::vector<Vec3> triple_points_on(Evaluator& ev, const SingularCurve& curve,
                                   const SingularScales& s, double spacing) {
  const auto& pts = curve.points;
  const size_t n = pts.size();
  std::vector<double> norm(n);
  for (size_t i = 0; i < n; ++i) norm[i] = ev.sample(pts[i], Derivatives::kHessian).hessian.norm();
  std::vector<Vec3> found;
  for (size_t k = 0; k < n; ++k) {
    const bool local_min =
        (k == 0 || norm[k] <= norm[k - 1]) && (k + 1 == n || norm[k] <= norm[k + 1]);
    if (!local_min || !(norm[k] < 0.2 * s.hess)) continue;
    const Vec3 a = pts[k > 0 ? k - 1 : 0], b = pts[std::min(k + 1, n - 1)];
    const double len = (b - a).norm();
    if (!(len > 0)) continue;
    const Vec3 dir = (b - a) / len;
    Vec3 best = pts[k];
    auto h_at = [&](double u) {
      const detail::Converged c = detail::converge_in_plane(ev, a + u * dir, dir, s, spacing);
      if (!c.ok) return std::numeric_limits<double>::infinity();
      const double v = ev.sample(c.p, Derivatives::kHessian).hessian.norm();
      best = c.p;
      return v;
    };
    constexpr double kGolden = 0.6180339887498949;
    double lo = 0, hi = len;
    double u1 = hi - kGolden * (hi - lo), u2 = lo + kGolden * (hi - lo);
    double f1 = h_at(u1), f2 = h_at(u2);
    for (int it = 0; it < 200 && hi - lo > 1e-15 * s.radius; ++it) {
      if (f1 <= f2) {
        hi = u2, u2 = u1, f2 = f1;
        u1 = hi - kGolden * (hi - lo);
        f1 = h_at(u1);
      } else {
        lo = u1, u1 = u2, f1 = f2;
        u2 = lo + kGolden * (hi - lo);
        f2 = h_at(u2);
      }
    }
    const double at = h_at(0.5 * (lo + hi));
    if (at <= 1e-6 * s.hess) found.push_back(best);
  }
  return found;
}

// Splits a curve by the form Q across it. Vertices where Q has rank one (kRankOne) in runs of
// two or more are degenerate stretches, pieces of their own: along a cuspidal edge det Q
// vanishes identically and its measured sign is rounding, so no pinch point is looked for
// there. Elsewhere a pinch point is where det Q changes sign between two vertices (vertices
// without a sign, kNoSign, are passed over): bisection on the curve finds the zero, and the
// curve is split there. Pinch points found are appended to `pinches`.
std::vector<SingularCurve> split_by_kind(Evaluator& ev, const SingularCurve& curve,
                                         const SingularScales& s, std::vector<Vec3>& pinches) {
  const auto& pts = curve.points;
  const size_t n = pts.size();
  auto ratio_at = [&](const std::vector<Vec3>& line, size_t i) {
    const Vec3 d = line[std::min(i + 1, line.size() - 1)] - line[i > 0 ? i - 1 : 0];
    return normal_form_det(ev.sample(line[i], Derivatives::kHessian).hessian, d.normalized(),
                           s.hess);
  };
  std::vector<double> ratio(n);
  for (size_t i = 0; i < n; ++i) ratio[i] = ratio_at(pts, i);
  auto rank_one = [&](size_t i) { return std::abs(ratio[i]) <= kRankOne; };
  auto no_sign = [&](size_t i) { return std::abs(ratio[i]) <= kNoSign; };
  std::vector<bool> degenerate(n);
  for (size_t i = 0; i < n; ++i)
    degenerate[i] = rank_one(i) && ((i > 0 && rank_one(i - 1)) || (i + 1 < n && rank_one(i + 1)));

  std::vector<SingularCurve> pieces;
  std::vector<bool> piece_degenerate;
  SingularCurve cur;
  cur.points.push_back(pts[0]);
  auto close_piece = [&](const Vec3& next_start, bool was_degenerate) {
    pieces.push_back(std::move(cur));
    piece_degenerate.push_back(was_degenerate);
    cur = SingularCurve{};
    cur.points.push_back(next_start);
  };
  double last_sign = no_sign(0) ? 0 : ratio[0];
  for (size_t i = 1; i < n; ++i) {
    if (degenerate[i] != degenerate[i - 1]) {
      // A degenerate stretch begins at i or ended at i − 1: the pieces share that vertex.
      if (degenerate[i]) {
        cur.points.push_back(pts[i]);
        close_piece(pts[i], false);
        continue;
      }
      close_piece(pts[i - 1], true);
      last_sign = 0;
    } else if (!degenerate[i] && !no_sign(i) && last_sign != 0 &&
               (ratio[i] > 0) != (last_sign > 0)) {
      // The sign changed on [i - 1, i]: bisect for det Q = 0 on the curve.
      const Vec3 t = (pts[i] - pts[i - 1]).normalized();
      Vec3 lo = pts[i - 1], hi = pts[i];
      const bool lo_positive = last_sign > 0;
      for (int it = 0; it < 80 && (hi - lo).norm() > 1e-14 * s.radius; ++it) {
        const Converged m = converge_in_plane(ev, 0.5 * (lo + hi), t, s, (hi - lo).norm());
        if (!m.ok) break;
        const double dm = normal_form_det(ev.sample(m.p, Derivatives::kHessian).hessian, t, s.hess);
        if (dm == 0) {
          lo = hi = m.p;
          break;
        }
        ((dm > 0) == lo_positive ? lo : hi) = m.p;
      }
      const Vec3 pinch = 0.5 * (lo + hi);
      cur.points.push_back(pinch);
      close_piece(pinch, false);
      pinches.push_back(pinch);
    }
    cur.points.push_back(pts[i]);
    if (!no_sign(i)) last_sign = ratio[i];
  }
  pieces.push_back(std::move(cur));
  piece_degenerate.push_back(degenerate[n - 1]);
  // The other pieces' kind: the sign their vertices share (none only at triple points, next to
  // pinch points or at the ends).
  for (size_t k = 0; k < pieces.size(); ++k) {
    SingularCurve& piece = pieces[k];
    double sum_neg = 0, sum_pos = 0;
    for (size_t i = 0; i < piece.points.size() && !piece_degenerate[k]; ++i)
      if (const double d = ratio_at(piece.points, i); std::abs(d) > kNoSign)
        (d < 0 ? sum_neg : sum_pos) += std::abs(d);
    piece.kind = sum_neg == 0 && sum_pos == 0 ? CurveKind::kDegenerate
                 : sum_neg > sum_pos          ? CurveKind::kCrossing
                                              : CurveKind::kIsolated;
  }
  if (pieces.size() == 1) pieces[0].closed = curve.closed;
  return pieces;
}

}  // namespace zeroset::detail
