// The pair pass over neighbours and the move of every floater.
#include "floater_state_detail.h"

#include <optional>

#include "zeroset/detail/bracket.h"

namespace zeroset::detail {
namespace {

// Where F = 0 lies along the normal line through p (F = value ≠ 0, ∇F = gradient, both finite,
// ∇F ≠ 0), as the signed distance t along n = ∇F/|∇F| (the zero at p + t·n), when the first-
// order estimate −F/|∇F| is unreliable; none when it is reliable or no zero lies within `reach`.
// Far from a simple root of a field of high degree (F = r²ⁿ − 1, n large) a Newton step covers
// about 1/(2n) of the way and |F|/|∇F| understates the distance as much, so the pull of A.4
// would crawl and floaters would look settled off the surface. One evaluation decides: where
// the full Newton step cuts |F| tenfold, first order is fine (near a simple root it cuts far
// more). Else (for r²ⁿ each step only divides F by e) the zero is bracketed by doubling steps
// and refined by the Illinois method (twenty evaluations or so).
std::optional<double> far_normal_root(Evaluator& ev, const Vec3& p, double value,
                                      const Vec3& gradient, double gnorm, double reach) {
  const Vec3 n = gradient / gnorm;
  const double towards = value > 0 ? -1.0 : 1.0;  // the side where F changes sign
  auto f_at = [&](double t) { return ev.value(p + (towards * t) * n); };
  double hi = std::min(std::abs(value) / gnorm, reach);
  double f_hi = f_at(hi);
  if (std::abs(f_hi) <= 0.1 * std::abs(value)) return std::nullopt;  // Newton converges
  double lo = 0, f_lo = value;
  while (std::isfinite(f_hi) && f_hi != 0 && (f_hi > 0) == (value > 0)) {
    if (hi >= reach) return std::nullopt;
    lo = hi, f_lo = f_hi;
    hi = std::min(2 * hi, reach);
    f_hi = f_at(hi);
  }
  if (!std::isfinite(f_hi)) return std::nullopt;  // undefined beyond: no reliable zero
  if (f_hi == 0) return towards * hi;
  return towards * refine_sign_change(f_at, lo, hi, f_lo, f_hi, 1e-12 * hi);
}

}  // namespace

// Builds the hash over the current positions and sizes the neighbour data in slot order (it is
// filled by pack_slot() in repulsion_and_move()'s parallel region).
void build_neighbours(FloaterState& sys) {
  const std::size_t n = floater_count(sys);
  // The largest σ and the floaters' bounding box, as evaluate_all() found them.
  const double largest = sys.largest_sigma;
  // The grid covers the floaters' bounding box within the clip's: a surface that lies flat
  // in its box gets few cells across it.
  Box3 region = sys.box;
  for (int k = 0; k < 3; ++k) {
    region.lo[k] = std::max(region.lo[k], sys.bounds.lo[k]);
    region.hi[k] = std::min(region.hi[k], sys.bounds.hi[k]);
  }
  if (region.is_empty()) region = sys.box;
  // Cells as large as the largest reach 3σ: a floater's neighbours lie in the 3×3×3 cells
  // around its own. (Smaller cells hold fewer candidates; measured on the Kummer scene, the
  // extra ranges and the larger grid cost as much as they save.)
  sys.hash.build(sys.pos, region, 3 * largest, sys.threads);
  if (sys.step_count % kResortInterval == 0) {
    permute_state(sys, sys.hash.order());
    sys.hash.build(sys.pos, region, 3 * largest, sys.threads);
  }
  fit(sys.packed, n);
  fit(sys.pid, n);
  // The filter reads whole groups of slots past a range's end: padding keeps that in bounds.
  for (auto* v : {&sys.fx, &sys.fy, &sys.fz, &sys.fcut}) {
    fit(*v, n + kFilterPad);
    std::fill(v->begin() + static_cast<std::ptrdiff_t>(n), v->end(), 0.0f);
  }
  // Single-precision coordinates for the prefilter: relative to the box centre, scaled into
  // [−1, 1] (see prefilter_threshold). An infinite coordinate makes the scale 0, and
  // then every candidate passes to the exact test (a NaN one never passes either test).
  const Vec3 centre = sys.box.center();
  double extent = 3 * largest;
  if (!sys.bounds.is_empty())
    extent = std::max({extent, (sys.bounds.lo - centre).cwiseAbs().maxCoeff(),
                       (sys.bounds.hi - centre).cwiseAbs().maxCoeff()});
  sys.prefilter_scale = extent > 0 && std::isfinite(extent) ? 1 / extent : 0;
}

namespace {

// The neighbour data of the floater at slot s (build_neighbours() sized the arrays).
void pack_slot(FloaterState& sys, std::size_t s) {
  const std::uint32_t i = sys.hash.order()[s];
  const Vec3 centre = sys.box.center();
  const double scale = sys.prefilter_scale;
  // A floater on a node has no tangent plane: it repels every sheet through the node.
  const Vec3 n = sys.pinned[i] ? Vec3::Zero() : sys.unit[i];
  sys.packed[s] = {sys.pos[i].x(), sys.pos[i].y(), sys.pos[i].z(), sys.sigma[i],
                   sys.smax[i],    n.x(),          n.y(),          n.z()};
  sys.pid[s] = sys.id[i];
  sys.fx[s] = static_cast<float>((sys.pos[i].x() - centre.x()) * scale);
  sys.fy[s] = static_cast<float>((sys.pos[i].y() - centre.y()) * scale);
  sys.fz[s] = static_cast<float>((sys.pos[i].z() - centre.z()) * scale);
  sys.fcut[s] = prefilter_threshold(3 * sys.sigma[i] * scale);
}

MoveConstants move_constants(const FloaterState& sys) {
  return {sys.opt.dt, desired_energy(sys), kMaxStepScene * sys.scene_radius,
          kMinRadius * sys.sigma_hat, kMaxRadius * sigma_max(sys)};
}

// Pair terms are computed in batches of about this many pairs, over several floaters:
// independent work for the processor, and the batch stays in the first-level cache.
constexpr std::size_t kPairBatch = 256;

// The neighbour search tests single-precision distances first (filter_box and
// filter_near), keeping every pair within reach 3·max(σ_i, σ_j) and a few more (see
// prefilter_threshold); the pair terms (pair_terms) then decide each
// exactly. This is the first test, per cell: the cell's floaters, then those of its forward
// cells within reach of the bounding box of the cell's floaters, copied into c (contiguous,
// for the second test, per floater); returns how many.
std::uint32_t gather_block(const FloaterState& sys, const SpatialHash::Run& run,
                           SpatialHash::ForwardWalk& walk, PairScratch& c) {
  const auto forward =
      std::span(c.ranges).first(static_cast<std::size_t>(walk.ranges(run.key, c.ranges)));
  const std::uint32_t own = run.last - run.first;
  std::size_t candidates = own;
  for (const auto& [first, last] : forward) candidates += last - first;
  c.reserve_candidates(candidates);
  const float *x = sys.fx.data(), *y = sys.fy.data(), *z = sys.fz.data(), *cut = sys.fcut.data();
  float lo[3] = {x[run.first], y[run.first], z[run.first]}, hi[3] = {lo[0], lo[1], lo[2]};
  float reach = 0;
  for (std::uint32_t s = run.first; s < run.last; ++s) {
    lo[0] = std::min(lo[0], x[s]);
    hi[0] = std::max(hi[0], x[s]);
    lo[1] = std::min(lo[1], y[s]);
    hi[1] = std::max(hi[1], y[s]);
    lo[2] = std::min(lo[2], z[s]);
    hi[2] = std::max(hi[2], z[s]);
    reach = std::max(reach, cut[s]);
    c.slot[s - run.first] = s;
  }
  const std::size_t m =
      own + filter_box(sys.filter, forward, x, y, z, cut, lo, hi, reach, c.slot.data() + own);
  for (std::size_t k = 0; k < m; ++k) {
    const std::uint32_t t = c.slot[k];
    c.x[k] = x[t];
    c.y[k] = y[t];
    c.z[k] = z[t];
    c.cut[k] = cut[t];
  }
  return static_cast<std::uint32_t>(m);
}

// Adds the batch's pair terms to the floaters' sums and empties it.
void accumulate_pairs(FloaterState& sys, PairBatch& batch, const PairConstants& k) {
  batch.accumulate(sys.opt.scaled_repulsion, k, reinterpret_cast<const double*>(sys.packed.data()),
                   sys.pid.data(), sys.pair_sums);
}

// docs/algorithms.md A.3–A.6 for floater i once its pair sums are complete (energy, σ_i³ ∂E_i/∂σ_i,
// desired velocity and graded fission radius): radius adaptation, constrained velocity with the
// φF and F_q·q̇ terms, bounded Euler step, clip projection; then its fate (judge_fate()) and its
// squared speed in radii per time unit and whether it is near equilibrium (for
// StepStats::rms_speed and near_equilibrium). Reads and writes floater i's entries only.
void move_one(FloaterState& sys, std::size_t i, const PairSums& sum, Evaluator& ev,
              const MoveConstants& k) {
  const double dt = k.dt, max_scene_step = k.max_scene_step;
  const double s = sys.sigma[i];
  const double denergy = sum.de / (s * s * s);
  const double rate = -sys.opt.radius_rate * (sum.e - k.e_hat) / (denergy + sys.opt.radius_damping);
  sys.new_sigma[i] = std::clamp(std::clamp(s + dt * rate, 0.5 * s, 2 * s), k.lo, k.hi);
  Vec3 p = sys.pos[i];
  bool outside = false;
  if (sys.pinned[i] >= kOnPoint) sys.new_sigma[i] = s;  // held on the singular set (B.7)
  if (sys.pinned[i] == kOnCurve) {
    // On a curve of the singular set: 1-D repulsion along it (chain_velocities()), bounded
    // like a tangential move; the floater stays on the polyline.
    const RailCurve& c = sys.rails[static_cast<std::size_t>(sys.rail[i])];
    const double along = sys.rail_push[i];
    const double limit = std::min(sys.opt.max_step_fraction * s, max_scene_step);
    const double move = std::clamp(dt * along, -limit, limit);
    sys.arc[i] = c.keep(sys.arc[i] + (std::isfinite(move) ? move : 0.0));
    p = c.at(sys.arc[i]);
  } else if (!sys.pinned[i]) {
    // Constrained velocity ṗ = P − [(F_x·P + F_q·q̇ + φF)/(F_x·F_x)] F_x, split into the
    // tangential part of P and the pull along the unit normal. Where ∇F vanishes (or F is
    // not finite) there is no normal: the floater moves by repulsion alone, and the pull
    // resumes as soon as it leaves the critical point.
    Vec3 tangential(sum.vx, sum.vy, sum.vz);  // the desired velocity
    Vec3 normal_move = Vec3::Zero();
    const Vec3& nrm = sys.unit[i];
    if (nrm.squaredNorm() > 0 && std::isfinite(sys.value[i])) {
      tangential -= nrm.dot(tangential) * nrm;
      double pull = -(sys.opt.feedback * sys.value[i] + sys.fq[i]) / sys.gnorm[i] * dt;
      // Off the surface by more than rounding: the φF term's first-order distance is checked
      // (far_normal_root) and replaced by the distance to the zero along the normal where it
      // is unreliable, so the pull converges whatever the degree of F.
      if (sys.value[i] != 0 && residual(sys.value[i], sys.gnorm[i]) > kCheckedResidual * s &&
          sys.gnorm[i] > 0 && std::isfinite(sys.gnorm[i]))
        if (const auto t =
                far_normal_root(ev, p, sys.value[i], sys.gnorm[i] * nrm, sys.gnorm[i], 2 * s))
          pull = sys.opt.feedback * dt * *t - sys.fq[i] / sys.gnorm[i] * dt;
      if (!std::isfinite(pull)) pull = std::copysign(max_scene_step, pull);
      normal_move = std::clamp(pull, -max_scene_step, max_scene_step) * nrm;
    }
    Vec3 tangential_move = dt * tangential;
    const double limit = std::min(sys.opt.max_step_fraction * s, max_scene_step);
    const double len = tangential_move.norm();
    if (len > limit) tangential_move *= limit / len;
    p += tangential_move + normal_move;
    if (sys.opt.clip_projection) {
      const Vec3 projected = sys.surface.clip.project(p);
      if (projected != p)
        p = sys.opt.clip_newton ? step_onto_clip_curve(ev, sys.surface.clip, projected, 0.5 * s)
                                : projected;
    } else {
      outside = !sys.surface.clip.contains(p);
    }
  }
  // A move that is not finite (F or its derivatives overflowed) leaves the floater where it
  // was and marks it a stray: no floater takes a non-finite position or radius.
  if (!p.allFinite() || !std::isfinite(sys.new_sigma[i])) {
    p = sys.pos[i];
    sys.new_sigma[i] = s;
    outside = true;
  }
  const double speed = (p - sys.pos[i]).norm() / dt;
  sys.new_pos[i] = p;
  sys.fate[i] = judge_fate(sys, i, sum.e, sys.new_sigma[i], sum.limit, speed, outside);
  if (sys.age[i] < std::numeric_limits<std::uint32_t>::max()) ++sys.age[i];
  const double v = speed / sys.new_sigma[i];
  sys.speed_sq[i] = v * v;
  sys.near_flag[i] = speed < sys.opt.equilibrium_speed * sys.new_sigma[i];
}

}  // namespace

// in each, in listing order): the result does not depend on the number of threads.
// The same pass grades the fission radii: σ_max^i ≤ σ_max^j + g·|r_ij| for every neighbour j (one
// relaxation sweep per step). Without it, where μ_i jumps (α_i drops from ~1 to ~0 once a
// floater's perimeter reaches across a node) the density wanted on either side differs by more
// than fission and death tolerate (a factor 1/δ), and they fight forever. Then every floater
// moves (move_one()), in the same parallel region.
void repulsion_and_move(FloaterState& sys) {
  const std::size_t n = floater_count(sys);
  for (auto* v : {&sys.graded, &sys.new_sigma, &sys.speed_sq}) fit(*v, n);
  fit(sys.new_pos, n);
  fit(sys.fate, n);
  fit(sys.near_flag, n);
  fit(sys.pair_sums, n);
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
  sys.chunk_speed.resize(chunks);
  sys.chunk_near.resize(chunks);
  sys.scratch.resize(static_cast<std::size_t>(sys.threads));
  const MoveConstants k = move_constants(sys);
  const PairConstants pk{sys.opt.repulsion, sys.opt.cos_weight ? 1.0 : 0.0, sys.opt.radius_grading,
                         sys.opt.energy_taper ? 1.0 : 0.0};
  const auto runs = sys.hash.runs();
  const auto order = sys.hash.order();
  const std::span<PairSums> sums(sys.pair_sums);
  ExceptionTrap trap;  // every loop body runs through it: all threads meet every barrier
#pragma omp parallel num_threads(sys.threads) if (n >= kParallelMin)
  {
    PairScratch& c = sys.scratch[static_cast<std::size_t>(worker_index())];
    Evaluator& ev = sys.evaluators[static_cast<std::size_t>(worker_index())];
#pragma omp for schedule(static)
    for (std::int64_t slot = 0; slot < static_cast<std::int64_t>(n); ++slot)
      trap.run([&] {
        const auto s = static_cast<std::size_t>(slot);
        pack_slot(sys, s);
        sums[s] = {0, 0, 0, 0, 0, sys.mu[order[s]] * sigma_max(sys)};
      });
    const auto layers = sys.hash.layers();
    const auto layer_runs = sys.hash.layer_runs();
    SpatialHash::ForwardWalk walk(sys.hash);
    for (std::int64_t parity = 0; parity < 2; ++parity) {
#pragma omp for schedule(dynamic, 1)
      for (std::int64_t l = 0; l < static_cast<std::int64_t>(layers.size()); ++l)
        trap.run([&] {
          const auto& layer = layers[static_cast<std::size_t>(l)];
          if ((layer.layer & 1) != parity) return;
          for (std::uint32_t r = layer.first; r < layer.last; ++r) {
            const auto& run = runs[layer_runs[r]];
            const std::uint32_t candidates = gather_block(sys, run, walk, c);
            for (std::uint32_t s = run.first; s < run.last; ++s) {
              // The later floaters of the cell and the forward cells' candidates.
              const SpatialHash::Range later{s - run.first + 1, candidates};
              const std::size_t kept = filter_near(sys.filter, {&later, 1}, c.x.data(), c.y.data(),
                                                   c.z.data(), c.cut.data(), sys.fx[s], sys.fy[s],
                                                   sys.fz[s], sys.fcut[s], c.near.data());
              c.batch.add(s, c.slot.data(), c.near.data(), kept);
              if (c.batch.pairs() >= kPairBatch) accumulate_pairs(sys, c.batch, pk);
            }
          }
          accumulate_pairs(sys, c.batch, pk);  // the layer's pairs are all in the sums
        });
    }
#pragma omp for schedule(dynamic, 256)
    for (std::int64_t slot = 0; slot < static_cast<std::int64_t>(n); ++slot)
      trap.run([&] {
        const auto s = static_cast<std::size_t>(slot);
        const std::uint32_t i = order[s];
        sys.graded[i] = sums[s].limit;
        move_one(sys, i, sums[s], ev, k);
      });
      // Summed per chunk in index order: the same on any number of threads.
#pragma omp for schedule(static)
    for (std::int64_t chunk = 0; chunk < static_cast<std::int64_t>(chunks); ++chunk)
      trap.run([&] {
        const std::size_t b = static_cast<std::size_t>(chunk) * kChunk;
        double sq = 0;
        std::size_t near = 0;
        for (std::size_t i = b; i < std::min(n, b + kChunk); ++i) {
          sq += sys.speed_sq[i];
          near += sys.near_flag[i];
        }
        sys.chunk_speed[static_cast<std::size_t>(chunk)] = sq;
        sys.chunk_near[static_cast<std::size_t>(chunk)] = near;
      });
  }
  trap.rethrow();
  sys.smax.swap(sys.graded);
}

// F_q·q̇ at every floater (exact parameter derivatives).
void parameter_terms(FloaterState& sys, std::span<const double> qdot) {
  const std::size_t n = floater_count(sys);
  fit(sys.fq, n);
  std::fill(sys.fq.begin(), sys.fq.end(), 0.0);
  if (std::all_of(qdot.begin(), qdot.end(), [](double v) { return v == 0; })) return;
  parallel_chunks(sys, n, [&](std::size_t b, std::size_t e, Evaluator& ev) {
    for (std::size_t i = b; i < e; ++i) {
      const FieldSample s = ev.sample(sys.pos[i], Derivatives::kParameters);
      double d = 0;
      for (std::size_t k = 0; k < qdot.size() && k < s.dq.size(); ++k) d += s.dq[k] * qdot[k];
      sys.fq[i] = std::isfinite(d) ? d : 0;
    }
  });
}

}  // namespace zeroset::detail
