// Rösch et al. §3.3: μ_i from the curvature (α_i) and singularity (β_i) estimators, and floaters
// held on nodes.
#include "floater_state_detail.h"

#include <numbers>

namespace zeroset::detail {

namespace {

// Newton's method on ∇F = 0 from p, staying within `reach` of it. Succeeds at a
// nondegenerate critical point that lies on the surface (F there is negligible against the
// change of F over the floater's radius): a node.
std::optional<Vec3> find_node(const FloaterState& sys, Evaluator& ev, const Vec3& p, double reach) {
  const auto c = find_critical_point(ev, p,
                                     {.iterations = kNodeIterations,
                                      .reach = reach,
                                      .min_conditioning = kNondegenerate,
                                      .tolerance = 1e-14,
                                      .length = sys.scene_radius});
  if (!c) return std::nullopt;
  const double change = c->largest * reach * reach;
  if (!(std::abs(c->value) <= 1e-8 * change)) return std::nullopt;  // off the surface
  return c->point;
}

// α_i = min_k |cos(∇F(p_i), ∇F(v_k))| over random points v_k on the floater's perimeter
// (radius σ_i in the tangent plane), each moved onto F = 0 by one Newton step.
void curvature_estimates(FloaterState& sys, std::size_t b, std::size_t e, int samples,
                         Evaluator& ev, std::vector<double>& alpha) {
  const std::size_t m = (e - b) * static_cast<std::size_t>(samples);
  // Kept per thread from call to call: every entry used is written first.
  auto& [x, y, z, f, gx, gy, gz] = sys.perimeter[static_cast<std::size_t>(worker_index())];
  for (auto* v : {&x, &y, &z, &f, &gx, &gy, &gz}) v->resize(m);
  // Stratified angles θ_j = 2π(j + phase)/samples: every direction around the floater gets
  // looked at. Each is the previous one turned by 2π/samples (one sine and cosine per
  // floater instead of one per sample).
  const double turn = 2 * std::numbers::pi / samples;
  const double turn_cos = std::cos(turn), turn_sin = std::sin(turn);
  for (std::size_t k = 0; k < e - b; ++k) {
    const std::size_t i = b + k;
    Vec3 t1, t2;
    tangent_basis(sys.unit[i], t1, t2);
    Rng rng(sys.opt.seed, sys.id[i], sys.step_count, Stream::kCurvature);
    const double theta = turn * rng.uniform();
    double c = std::cos(theta), sn = std::sin(theta);
    for (int j = 0; j < samples; ++j) {
      const Vec3 v = sys.pos[i] + sys.sigma[i] * (c * t1 + sn * t2);
      const double next_c = c * turn_cos - sn * turn_sin;
      sn = sn * turn_cos + c * turn_sin;
      c = next_c;
      const std::size_t s = k * samples + j;
      x[s] = v.x();
      y[s] = v.y();
      z[s] = v.z();
    }
  }
  ev.values_gradients(x, y, z, f, gx, gy, gz);
  for (std::size_t s = 0; s < m; ++s) {
    const Vec3 g(gx[s], gy[s], gz[s]);
    const double g2 = g.squaredNorm();
    if (!(g2 > 0) || !std::isfinite(g2) || !std::isfinite(f[s])) continue;
    Vec3 step = surface_newton_step(f[s], g);
    const double limit = sys.sigma[b + s / samples];
    if (step.norm() > limit) step *= limit / step.norm();
    x[s] += step.x();
    y[s] += step.y();
    z[s] += step.z();
  }
  ev.values_gradients(x, y, z, f, gx, gy, gz);
  for (std::size_t k = 0; k < e - b; ++k) {
    const Vec3& n = sys.unit[b + k];
    if (n.squaredNorm() == 0) {
      alpha[k] = 0;  // ∇F vanishes here: as bent as it gets
      continue;
    }
    double a = 1;
    for (int j = 0; j < samples; ++j) {
      const std::size_t s = k * samples + j;
      const Vec3 g(gx[s], gy[s], gz[s]);
      const double len = g.norm();
      const double c = (len > 0 && std::isfinite(len)) ? std::abs(n.dot(g) / len) : 0.0;
      a = std::min(a, c);
    }
    alpha[k] = a;
  }
}

// Serial, so which floater takes a node does not depend on threads: the first candidate in
// storage order whose Newton iteration lands on a node no floater holds yet.
void snap_candidates(FloaterState& sys, const std::vector<std::uint8_t>& candidate) {
  std::vector<Vec3> held;
  for (std::size_t i = 0; i < floater_count(sys); ++i)
    if (sys.pinned[i]) held.push_back(sys.pos[i]);
  for (std::size_t i = 0; i < floater_count(sys); ++i) {
    if (!candidate[i]) continue;
    const auto node = find_node(sys, sys.evaluators[0], sys.pos[i], sys.sigma[i]);
    if (!node || !sys.surface.clip.contains(*node)) continue;
    const bool taken = std::any_of(held.begin(), held.end(), [&](const Vec3& h) {
      return (h - *node).norm() < 0.5 * sys.sigma[i];
    });
    if (taken) continue;
    sys.pos[i] = *node;
    sys.pinned[i] = kOnNode;
    held.push_back(*node);
    widen(sys.bounds, *node);
  }
}

}  // namespace

// Every estimator_interval steps: μ_i for the fission radii, and floaters that have come
// near a node are snapped onto it.
void update_estimators(FloaterState& sys) {
  const RadiusAdapt mode = sys.opt.radius_adapt;
  const std::size_t n = floater_count(sys);
  const bool need_alpha = mode == RadiusAdapt::kCurvature || mode == RadiusAdapt::kMixed;
  const bool need_beta = mode == RadiusAdapt::kSingular || mode == RadiusAdapt::kMixed;
  const bool need_hessian = need_beta || sys.opt.snap_to_nodes;
  if (!need_alpha && !need_hessian) return;
  std::vector<std::uint8_t> candidate(n, 0);
  const int samples = sys.opt.curvature_samples;
  parallel_chunks(sys, n, [&](std::size_t b, std::size_t e, Evaluator& ev) {
    const std::size_t m = e - b;
    std::vector<double> alpha(m, 1.0), beta(m, 1.0);
    if (need_hessian) {
      // F, ∇F and the Hessian at the chunk's floaters, in one batched evaluation.
      auto& v = sys.hessian_batch[static_cast<std::size_t>(worker_index())];
      for (auto& a : v) a.resize(m);
      for (std::size_t k = 0; k < m; ++k) {
        v[0][k] = sys.pos[b + k].x();
        v[1][k] = sys.pos[b + k].y();
        v[2][k] = sys.pos[b + k].z();
      }
      ev.values_gradients_hessians(v[0], v[1], v[2], v[3], v[4], v[5], v[6],
                                   {v[7], v[8], v[9], v[10], v[11], v[12]});
      for (std::size_t k = 0; k < m; ++k) {
        const std::size_t i = b + k;
        const Vec3 gradient(v[4][k], v[5][k], v[6][k]);
        Mat3 hessian;
        hessian << v[7][k], v[8][k], v[9][k],  //
            v[8][k], v[10][k], v[11][k],       //
            v[9][k], v[11][k], v[12][k];
        // Away from singular points the Hessian is regular and only |r| matters: the
        // eigenvalues are wanted for a singular Hessian or a floater that may snap.
        // The distance to the singular set found (curves too, where the Newton step below
        // may see no critical point ahead), when it is within the index's reach.
        const double found = singular_set_distance(sys, sys.pos[i]);
        const auto regular = regular_critical_step(gradient, hessian);
        const bool may_snap = sys.opt.snap_to_nodes && !sys.pinned[i];
        if (regular && !(may_snap && regular->norm() < kSnapFraction * sys.sigma[i])) {
          beta[k] = std::min(std::min(regular->norm(), found) / sys.singular_scale, 1.0);
          continue;
        }
        const CriticalStep c = critical_step(gradient, hessian);
        const double r =
            std::min(c.reaches ? c.step.norm() : std::numeric_limits<double>::infinity(), found);
        beta[k] = std::isfinite(r) ? std::min(r / sys.singular_scale, 1.0) : 1.0;
        candidate[i] =
            may_snap && r < kSnapFraction * sys.sigma[i] && c.smallest > kNondegenerate * c.largest;
      }
    }
    if (need_alpha) curvature_estimates(sys, b, e, samples, ev, alpha);
    if (mode == RadiusAdapt::kWitkinHeckbert) return;
    for (std::size_t k = 0; k < m; ++k) {
      double f = 1;
      switch (mode) {
        case RadiusAdapt::kCurvature:
          f = alpha[k];
          break;
        case RadiusAdapt::kSingular:
          f = beta[k];
          break;
        case RadiusAdapt::kMixed:
          f = alpha[k] / 3 + 2 * beta[k] / 3;
          break;
        case RadiusAdapt::kWitkinHeckbert:
          break;
      }
      // Averaged with the previous estimate: α_i comes from random perimeter points, and a
      // σ_max^i that jumps from update to update triggers fissions and deaths for nothing.
      const double mu = std::clamp(f, sys.opt.min_radius_factor, 1.0);
      sys.mu[b + k] = sys.opt.average_radius_factor ? 0.5 * (sys.mu[b + k] + mu) : mu;
    }
  });
  if (sys.opt.snap_to_nodes) snap_candidates(sys, candidate);
}

// After a parameter change nodes move: each pinned floater follows its node by Newton's
// method, and is released when the node has gone (or turned degenerate).
void track_nodes(FloaterState& sys) {
  for (std::size_t i = 0; i < floater_count(sys); ++i) {
    if (sys.pinned[i] != kOnNode) continue;
    const auto node = find_node(sys, sys.evaluators[0], sys.pos[i], sys.sigma[i]);
    if (node && sys.surface.clip.contains(*node))
      sys.pos[i] = *node;
    else
      sys.pinned[i] = 0;
  }
}

}  // namespace zeroset::detail
