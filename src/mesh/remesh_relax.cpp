// The remesher's relaxation, projection and output (include/zeroset/mesh/remesh.h).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "remesh_detail.h"
#include "zeroset/mesh/mesh_ops.h"
#include "zeroset/surface/analysis.h"

namespace zeroset::detail {

// Newton onto F = 0 (onto the clip curve F = 0 ∩ G = 0 for kClip vertices) from `from`.
// False when it does not get there within `reach`, or meets a point where F or ∇F is not
// finite or ∇F vanishes.
bool Remesher::project(bool on_clip, Vec3& p, double reach) {
  Evaluator& e = pool.local();
  const Vec3 from = p;
  const double tolerance = 1e-14 * (1 + from.norm());
  if (on_clip) {
    p = project_onto_clip_curve(e, surface.clip, from, reach);
  } else {
    for (int it = 0; it < 12; ++it) {
      Vec3 g;
      const double f = e.value_gradient(p, g);
      const double g2 = g.squaredNorm();
      if (!std::isfinite(f) || !(g2 > 0) || !std::isfinite(g2)) return false;
      const Vec3 step = surface_newton_step(f, g);
      p += step;
      if (!((p - from).norm() <= reach)) return false;
      // Within the tolerance before the step: the step took it to the rounding floor (more
      // steps only wander there).
      if (step.norm() <= tolerance) break;
    }
  }
  Vec3 g;
  const double f = e.value_gradient(p, g);
  return (p - from).norm() <= reach && has_residual(f, g.norm()) &&
         residual(f, g.norm()) <= tolerance;
}

// The two border neighbours of a clip vertex (kNone where it has not exactly two).
std::array<std::uint32_t, 2> Remesher::border_neighbours(std::uint32_t v) const {
  std::array<std::uint32_t, 2> out{kNone, kNone};
  int count = 0;
  for (std::uint32_t t : vt[v])
    for (std::uint32_t w : mesh.triangles[t]) {
      std::uint32_t et[2];
      if (w == v || w == out[0] || edge_tris(v, w, et) != 1) continue;
      if (count < 2) out[static_cast<size_t>(count)] = w;
      ++count;
    }
  return count == 2 ? out : std::array<std::uint32_t, 2>{kNone, kNone};
}

void Remesher::build_border_chains() {
  chain_start.assign(1, 0);
  chain_vertex.clear();
  const size_t n = mesh.positions.size();
  if (std::none_of(kind.begin(), kind.end(), [](std::uint8_t k) { return k == kClip; })) return;
  std::vector<std::array<std::uint32_t, 2>> nb(n, {kNone, kNone});
  for (std::uint32_t v = 0; v < n; ++v)
    if (alive_vertex[v] && kind[v] == kClip) nb[v] = border_neighbours(v);
  std::vector<std::uint8_t> done(n, 0);
  auto walk = [&](std::uint32_t start, std::uint32_t next) {
    const size_t first = chain_vertex.size();
    chain_vertex.push_back(start);
    std::uint32_t prev = start, cur = next;
    while (cur != kNone && cur != start && kind[cur] == kClip && !done[cur]) {
      chain_vertex.push_back(cur);
      done[cur] = 1;
      const std::uint32_t nx = nb[cur][0] == prev ? nb[cur][1] : nb[cur][0];
      prev = cur, cur = nx;
    }
    if (cur == kNone) {  // an open end: leave the chain
      chain_vertex.resize(first);
      return;
    }
    chain_vertex.push_back(cur);  // the far end (the start again on a loop)
    chain_start.push_back(static_cast<std::uint32_t>(chain_vertex.size()));
  };
  // Chains from a vertex that does not slide.
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!alive_vertex[v] || kind[v] != kLocked || vt[v].empty()) continue;
    for (std::uint32_t t : vt[v])
      for (std::uint32_t w : mesh.triangles[t])
        if (w != v && kind[w] == kClip && !done[w] && (nb[w][0] == v || nb[w][1] == v)) {
          done[w] = 1;
          walk(v, w);
        }
  }
  // Closed loops of sliding vertices.
  for (std::uint32_t v = 0; v < n; ++v)
    if (kind[v] == kClip && !done[v] && nb[v][0] != kNone) {
      done[v] = 1;
      walk(v, nb[v][0]);
    }
}

// Targets for the clip vertices: each chain of them along the border (between two vertices
// that do not slide, or a closed loop from its first vertex) evenly spaced by arc length on
// its polyline. Relaxing by neighbour midpoints instead converges as slowly as a 1-D Jacobi
// iteration (about 1% per step on a chain of 20); this lands in one step up to the
// polyline's error.
void Remesher::border_targets(std::vector<Vec3>& target, std::vector<std::uint8_t>& has) {
  std::vector<double> s;
  for (size_t c = 0; c + 1 < chain_start.size(); ++c) {
    const std::uint32_t* chain = chain_vertex.data() + chain_start[c];
    const size_t size = chain_start[c + 1] - chain_start[c];
    s.assign(size, 0.0);
    for (size_t i = 1; i < size; ++i)
      s[i] = s[i - 1] + (mesh.positions[chain[i]] - mesh.positions[chain[i - 1]]).norm();
    const double total = s.back();
    size_t seg = 1;
    for (size_t i = 1; i + 1 < size; ++i) {
      const double want = total * static_cast<double>(i) / static_cast<double>(size - 1);
      while (seg + 1 < size && s[seg] < want) ++seg;
      const double len = s[seg] - s[seg - 1];
      const double u = len > 0 ? std::clamp((want - s[seg - 1]) / len, 0.0, 1.0) : 0.0;
      target[chain[i]] = (1 - u) * mesh.positions[chain[seg - 1]] + u * mesh.positions[chain[seg]];
      has[chain[i]] = 1;
    }
  }
}

void Remesher::build_rings() {
  const size_t n = mesh.positions.size();
  rtri.clear();
  ring_start.assign(n + 1, 0);
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    if (alive_tri[t]) {
      rtri.push_back(mesh.triangles[t]);
      for (std::uint32_t v : mesh.triangles[t]) ++ring_start[v + 1];
    }
  for (size_t v = 0; v < n; ++v) ring_start[v + 1] += ring_start[v];
  ring_tri.resize(ring_start[n]);
  std::vector<std::uint32_t> fill(ring_start.begin(), ring_start.end() - 1);
  for (std::uint32_t t = 0; t < rtri.size(); ++t)
    for (std::uint32_t v : rtri[t]) ring_tri[fill[v]++] = t;
  free_vs.clear(), clip_vs.clear();
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!alive_vertex[v] || ring_start[v] == ring_start[v + 1]) continue;
    if (kind[v] == kFree && !pinch_held[v]) free_vs.push_back(v);
    if (kind[v] == kClip) clip_vs.push_back(v);
  }
  build_border_chains();
  rings_stale = false;
}

void Remesher::triangle_normals() {
  if (rings_stale) build_rings();
  const long long nt = static_cast<long long>(rtri.size());
  rnormal.resize(rtri.size());
  rarea.resize(rtri.size());
  rmoment.resize(rtri.size());
  const auto& p = mesh.positions;
#pragma omp parallel for num_threads(workers) schedule(static)
  for (long long t = 0; t < nt; ++t) {
    const Tri& tr = rtri[t];
    rnormal[t] = area_normal(p[tr[0]], p[tr[1]], p[tr[2]]);
    rarea[t] = rnormal[t].norm();
    rmoment[t] = rarea[t] * (p[tr[0]] + p[tr[1]] + p[tr[2]]);
  }
}

void Remesher::update_gradients(const std::vector<std::uint32_t>& vs) {
  std::vector<std::uint32_t> todo;
  std::vector<Vec3> pts;
  for (std::uint32_t v : vs)
    if (!(grad_at[v] == mesh.positions[v])) todo.push_back(v), pts.push_back(mesh.positions[v]);
  std::vector<double> f;
  std::vector<Vec3> g;
  values_gradients(pool, workers, pts, f, g);
  for (size_t i = 0; i < todo.size(); ++i) grad_at[todo[i]] = pts[i], grad[todo[i]] = g[i];
}

// One Jacobi step: every free vertex to the area-weighted centroid of its ring, in the
// tangent plane, and every clip vertex to its border target along the clip curve; then back
// onto F = 0 (the curve). Moves that would turn a triangle over or flatten it are undone.
// Returns the largest move over L.
//
// A step in the tangent plane and back onto F = 0 lands short of the point whose tangent
// plane holds the centroid, by about the curvature times the centroid's height over the plane:
// next to a node that factor comes close to one, and such a vertex crept on for 40 to 120
// settling steps while every other vertex was at rest. With step_repeats, a vertex that moved
// by rest_move L or more repeats its step from where it landed, towards the same centroid.
double Remesher::relax_step() {
  ++stats.relax_steps;
  triangle_normals();
  const size_t nv = mesh.positions.size();
  std::vector<Vec3> border_target;
  std::vector<std::uint8_t> has_target;
  if (!clip_vs.empty()) {
    border_target.resize(nv);
    has_target.assign(nv, 0);
    border_targets(border_target, has_target);
  }
  // F and ∇F in batches (much cheaper per point than one at a time): at the current positions
  // for the tangent planes (cached for the vertices that did not move), then at the moved ones
  // for Newton's steps onto F = 0.
  update_gradients(free_vs);
  std::vector<Vec3> next = mesh.positions;
  const long long nf = static_cast<long long>(free_vs.size());
  std::vector<Vec3> start(free_vs.size()), centroid(free_vs.size());
  std::vector<std::uint8_t> state(free_vs.size(), 0);  // 0 failed, 1 moving, 2 on F = 0
#pragma omp parallel for num_threads(workers) schedule(static)
  for (long long i = 0; i < nf; ++i) {
    const std::uint32_t v = free_vs[i];
    const Vec3& p = mesh.positions[v];
    Vec3 c = Vec3::Zero();
    double area = 0;
    for (std::uint32_t k = ring_start[v]; k < ring_start[v + 1]; ++k)
      c += rmoment[ring_tri[k]], area += rarea[ring_tri[k]];
    const Vec3& gv = grad[v];
    if (!(area > 0) || !(gv.norm() > 0) || !gv.allFinite()) continue;
    c *= 1 / (3 * area);  // rmoment holds three times the moments
    const Vec3 u = gv.normalized();
    Vec3 d = c - p;
    d -= d.dot(u) * u;
    start[i] = p + d;
    centroid[i] = c;
    state[i] = 1;
  }
  ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(dynamic, 16)
  for (long long i = 0; i < static_cast<long long>(clip_vs.size()); ++i)
    trap.run([&] {
      const std::uint32_t v = clip_vs[i];
      if (!has_target[v]) return;
      Vec3 q = border_target[v];
      if (project(true, q, 0.5 * L) && surface.clip.contains(q, 1e-9 * L)) next[v] = q;
    });
  trap.rethrow();
  // Newton's method onto F = 0 for the free vertices, in chunks of kNewtonChunk (each chunk's
  // points evaluated together in structure-of-arrays batches, its data staying in the cache),
  // each round only at the points not there yet; the chunks in parallel.
  std::vector<Vec3> at = start;
  const long long chunks = (nf + kNewtonChunk - 1) / kNewtonChunk;
#pragma omp parallel num_threads(workers)
  {
    std::vector<std::uint32_t> live;
    GradientBatch batch;
#pragma omp for schedule(dynamic, 1)
    for (long long c = 0; c < chunks; ++c)
      trap.run([&] {
        const long long e = std::min(nf, (c + 1) * kNewtonChunk);
        live.clear();
        for (long long i = c * kNewtonChunk; i < e; ++i)
          if (state[i] == 1) live.push_back(static_cast<std::uint32_t>(i));
        for (int it = 0; it < kBatchNewtonSteps + 1 && !live.empty(); ++it) {
          const size_t m = live.size();
          batch.evaluate(pool.local(), m, [&](size_t k) -> const Vec3& { return at[live[k]]; });
          const std::vector<double>& f = batch.f;
          const bool last = it == kBatchNewtonSteps;
          size_t kept = 0;
          for (size_t k = 0; k < m; ++k) {
            const std::uint32_t i = live[k];
            const Vec3 g = batch.gradient(k);
            const double gn = g.norm();
            if (!has_residual(f[k], gn)) {
              state[i] = 0;
              continue;
            }
            if (residual(f[k], gn) <= 1e-14 * (1 + at[i].norm())) {
              state[i] = 2;
              // ∇F there is what the next step's tangent plane needs if the vertex stays there.
              const std::uint32_t v = free_vs[i];
              grad_at[v] = at[i], grad[v] = g;
              continue;
            }
            if (last) {
              live[kept++] = i;
              continue;
            }
            const Vec3 step = surface_newton_step(f[k], g);
            at[i] += step;
            if (it == 0 && step.norm() <= kShortNewtonStep * L) {
              // Left about the curvature times the step squared off F = 0 (1e-6 L), with ∇F from
              // where the step began as its tangent plane's: no second evaluation.
              state[i] = 2;
              const std::uint32_t v = free_vs[i];
              grad_at[v] = at[i], grad[v] = g;
              continue;
            }
            live[kept++] = i;
          }
          live.resize(kept);
        }
      });
  }
  trap.rethrow();
  auto inside = [&](const Vec3& q) {
    return surface.clip.is_empty_spec() || surface.clip.contains(q, 1e-9 * L);
  };
#pragma omp parallel for num_threads(workers) schedule(dynamic, 256)
  for (long long i = 0; i < nf; ++i)
    trap.run([&] {
      if (state[i] == 0) return;
      // Not there yet after the batched steps (rare): one at a time from the start.
      if (state[i] == 1) {
        Vec3 q = start[i];
        if (project(false, q, 0.5 * L)) at[i] = q, state[i] = 2;
      }
      const bool ok = state[i] == 2 && (at[i] - start[i]).norm() <= 0.5 * L && inside(at[i]);
      if (!ok) return;
      const Vec3& p = mesh.positions[free_vs[i]];
      for (int k = 0; k < step_repeats && (at[i] - p).norm() >= opt.rest_move * L; ++k) {
        Vec3 g;
        pool.local().value_gradient(at[i], g);
        if (!(g.norm() > 0) || !g.allFinite()) break;
        const Vec3 u = g.normalized();
        Vec3 d = centroid[i] - at[i];
        d -= d.dot(u) * u;
        Vec3 q = at[i] + d;
        if (!project(false, q, 0.5 * L) || !inside(q)) break;
        at[i] = q;
      }
      next[free_vs[i]] = at[i];
    });
  trap.rethrow();
  return apply_guarded(next);
}

// The step on the workers worker_choice picks, timed for it (the step's result does not
// depend on their number).
double Remesher::relax() {
  if (!measure_workers) return relax_step();
  workers = worker_choice.next();
  const auto t0 = std::chrono::steady_clock::now();
  const double moved = relax_step();
  worker_choice.took(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return moved;
}

// Moves every vertex to `next` except where a triangle would turn over or flatten: there
// the triangle's vertices stay (repeated until no triangle is bad). rnormal must be current.
double Remesher::apply_guarded(std::vector<Vec3>& next) {
  const size_t nv = mesh.positions.size();
  const long long n = static_cast<long long>(nv);
  std::vector<std::uint8_t> moved(nv);
#pragma omp parallel for num_threads(workers) schedule(static)
  for (long long v = 0; v < n; ++v) moved[v] = next[v] != mesh.positions[v];
  // Whether packed triangle t is bad after the moves. An unmoved one is not: its corners are
  // where they were when it was judged good.
  auto is_bad = [&](std::uint32_t t) {
    const Tri& tr = rtri[t];
    if (!moved[tr[0]] && !moved[tr[1]] && !moved[tr[2]]) return false;
    const Vec3& before = rnormal[t];
    const Vec3 after = area_normal(next[tr[0]], next[tr[1]], next[tr[2]]);
    // |after| > min_area and after·before > |after| |before| / 2, squared: no square root.
    const double area2 = after.squaredNorm(), dot = after.dot(before);
    return !(area2 > min_area * min_area && dot > 0 &&
             4 * dot * dot > area2 * rarea[t] * rarea[t]) ||
           (!agrees_with_gradient(after, tr) && agrees_with_gradient(before, tr));
  };
  std::vector<std::uint32_t> judged, reverted;
  auto revert = [&](std::uint32_t t) {
    for (std::uint32_t v : rtri[t])
      if (moved[v])
        next[v] = mesh.positions[v], moved[v] = 0, ++stats.reverted_moves, reverted.push_back(v);
  };
  // The first round judges every triangle, each later one only those with a corner the round
  // before put back. Each round undoes at least one move (a bad triangle has a moved corner),
  // so this ends, with no bad triangle left.
  std::vector<std::uint8_t> bad(rtri.size()), queued;
  const long long nt = static_cast<long long>(rtri.size());
#pragma omp parallel for num_threads(workers) schedule(static)
  for (long long t = 0; t < nt; ++t) bad[t] = is_bad(static_cast<std::uint32_t>(t));
  for (std::uint32_t t = 0; t < rtri.size(); ++t)
    if (bad[t]) revert(t);
  while (!reverted.empty()) {
    if (queued.empty()) queued.assign(rtri.size(), 0);
    judged.clear();
    for (std::uint32_t v : reverted)
      for (std::uint32_t k = ring_start[v]; k < ring_start[v + 1]; ++k)
        if (!queued[ring_tri[k]]) queued[ring_tri[k]] = 1, judged.push_back(ring_tri[k]);
    for (std::uint32_t t : judged) queued[t] = 0;
    const long long nj = static_cast<long long>(judged.size());
#pragma omp parallel for num_threads(workers) schedule(static)
    for (long long j = 0; j < nj; ++j) bad[j] = is_bad(judged[j]);
    reverted.clear();
    for (long long j = 0; j < nj; ++j)
      if (bad[j]) revert(judged[j]);
  }
  double worst = 0;  // squared
#pragma omp parallel for num_threads(workers) schedule(static) reduction(max : worst)
  for (long long v = 0; v < n; ++v) {
    if (!moved[v]) continue;
    worst = std::max(worst, (next[v] - mesh.positions[v]).squaredNorm());
    mesh.positions[v] = next[v];
  }
  return L > 0 ? std::sqrt(worst) / L : 0.0;
}

// Newton projection of every moving vertex onto F = 0 (the clip curve for kClip), guarded.
void Remesher::final_projection() {
  std::vector<std::uint32_t> todo, polish;
  std::vector<Vec3> pts, moved;
  std::vector<double> f;
  std::vector<Vec3> g;
  for (int round = 0; round < 3; ++round) {
    // F and ∇F at every moving vertex in one batch. Free vertices already on F = 0
    // (relaxation's Newton steps left most there) take one more Newton step in the first
    // round, also batched, kept where it stays on F = 0; Newton one vertex at a time only at
    // the others.
    todo.clear(), pts.clear(), polish.clear(), moved.clear();
    for (std::uint32_t v = 0; v < mesh.positions.size(); ++v)
      if (alive_vertex[v] && kind[v] != kLocked && !vt[v].empty())
        todo.push_back(v), pts.push_back(mesh.positions[v]);
    values_gradients(pool, workers, pts, f, g);
    size_t kept = 0;
    for (size_t k = 0; k < todo.size(); ++k) {
      const double gn = g[k].norm();
      if (kind[todo[k]] == kClip || !has_residual(f[k], gn) ||
          residual(f[k], gn) > 1e-14 * (1 + pts[k].norm()))
        todo[kept++] = todo[k];
      else if (round == 0)
        polish.push_back(todo[k]), moved.push_back(pts[k] + surface_newton_step(f[k], g[k]));
    }
    todo.resize(kept);
    if (todo.empty() && polish.empty()) break;
    std::vector<Vec3> next = mesh.positions;
    values_gradients(pool, workers, moved, f, g);
    for (size_t k = 0; k < polish.size(); ++k) {
      const double gn = g[k].norm();
      if (has_residual(f[k], gn) && residual(f[k], gn) <= 1e-14 * (1 + moved[k].norm()))
        next[polish[k]] = moved[k];
    }
    const long long n = static_cast<long long>(todo.size());
    ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(dynamic, 256)
    for (long long k = 0; k < n; ++k)
      trap.run([&] {
        const std::uint32_t v = todo[k];
        Vec3 q = mesh.positions[v];
        if (project(kind[v] == kClip, q, 0.25 * L)) next[v] = q;
      });
    trap.rethrow();
    triangle_normals();
    apply_guarded(next);
  }
}

void Remesher::compact() {
  std::vector<Tri> tris;
  tris.reserve(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    if (alive_tri[t]) tris.push_back(mesh.triangles[t]);
  mesh.triangles.swap(tris);
  mesh.normals.clear();
  remove_unreferenced_vertices(mesh);
}

void Remesher::measure_residual() {
  std::vector<double> f;
  std::vector<Vec3> g;
  values_gradients(pool, workers, mesh.positions, f, g);
  // Locked vertices are not ours to measure: singular points and curves have ∇F = 0.
  std::vector<std::uint8_t> moving(mesh.positions.size(), 1);
  for (const MeshCurve& c : mesh.curves)
    for (std::uint32_t v : c.vertices) moving[v] = 0;
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    if (!std::isfinite(f[v])) {
      ++stats.undefined_vertices;
      stats.max_residual = std::numeric_limits<double>::max();
      continue;
    }
    if (!moving[v]) continue;
    const bool at_point = std::any_of(stats.singular_points.begin(), stats.singular_points.end(),
                                      [&](const Vec3& q) { return q == mesh.positions[v]; });
    if (at_point || !has_residual(f[v], g[v].norm())) continue;
    stats.max_residual = std::max(stats.max_residual, residual(f[v], g[v].norm()));
  }
}

}  // namespace zeroset::detail
