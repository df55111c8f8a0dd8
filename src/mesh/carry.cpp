// Carrying a mesh to new parameter values (docs/meshing.md, "Carrying a mesh").
#include "zeroset/mesh/carry.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include <fmt/core.h>

#include "mesh_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/error.h"
#include "zeroset/mesh/adjacency.h"
#include "zeroset/mesh/mesh_ops.h"
#include "zeroset/mesh/quality.h"
#include "zeroset/surface/analysis.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset {
namespace {

using Clock = std::chrono::steady_clock;

// A vertex within this many mean edge lengths of a singular point moves with the point: ∇F
// vanishes there, so the parameter term −(F_q·Δq)∇F/|∇F|² means nothing, and the cone around
// a node moves with it to first order. Triangles and vertices this close are left out of the
// flip, angle and residual checks too (∇F has no direction there).
constexpr double kNodeReach = 2;
// Newton onto the new surface stops at |F|/|∇F| below this × the mean edge length.
constexpr double kProjectionTolerance = 1e-12;
// Steps of Newton's method onto ∇F = 0 for a vertex of a singular curve.
constexpr int kCurveNewtonSteps = 8;

// The singular points (and the number of singular curves) of `s`: the known points when the
// surface has them, else what find_singular_set() finds.
CarrySingularSet singular_info(const Surface& s, const CarryOptions& o) {
  CarrySingularSet info;
  if (s.singular_points_fn) {
    info.points = s.singular_points();
    return info;
  }
  if (o.singular_cells <= 0 || !s.clip.is_bounded()) return info;
  const SingularSet set = find_singular_set(s, {.cells = o.singular_cells});
  for (const SingularPoint& p : set.points) info.points.push_back(p.position);
  info.curves = static_cast<int>(set.curves.size());
  if (set.has_singular_sheet) info.curves = -1;  // a sheet of singular points: never carried
  return info;
}

void check_options(const CarryOptions& o) {
  auto bad = [](const char* name, double v, const char* why) {
    throw InvalidArgument(name, fmt::format("{}", v), why);
  };
  if (o.improve_steps < 0 || o.improve_steps > 1000)
    bad("improve_steps", o.improve_steps, "must be in [0, 1000]");
  if (!(o.max_move_edges > 0 && std::isfinite(o.max_move_edges)))
    bad("max_move_edges", o.max_move_edges, "must be > 0");
  if (!(o.max_residual_edges > 0 && std::isfinite(o.max_residual_edges)))
    bad("max_residual_edges", o.max_residual_edges, "must be > 0");
  if (!(o.min_angle_deg >= 0 && o.min_angle_deg < 60))
    bad("min_angle_deg", o.min_angle_deg, "must be in [0, 60)");
  if (o.singular_cells < 0) bad("singular_cells", o.singular_cells, "must be ≥ 0");
  if (o.threads < 0) bad("threads", o.threads, "must be ≥ 0");
  detail::check_improve_options(o.improve);
}

CarryResult failed(CarryFailure why, std::string reason, Clock::time_point t0) {
  CarryResult r;
  r.failure = why;
  r.reason = std::move(reason);
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return r;
}

// Per vertex: the mean length of its edges, the singular point within kNodeReach mean edges,
// and whether it lies on a singular curve of the mesh or next to one.
struct VertexFrame {
  std::vector<double> edge;       // mean incident edge length
  std::vector<int> nearest_node;  // index into the old singular points within reach, or −1
  std::vector<std::uint8_t> on_curve, near_curve;
  double mean_edge = 0;
};

VertexFrame vertex_frame(const Mesh& mesh, const std::vector<Vec3>& nodes) {
  VertexFrame fr;
  const size_t nv = mesh.vertex_count();
  const MeshAdjacency adj = build_adjacency(mesh);
  fr.edge.assign(nv, 0);
  std::vector<int> count(nv, 0);
  double total = 0;
  for (const auto& e : adj.edges) {
    const double len = (mesh.positions[e[0]] - mesh.positions[e[1]]).norm();
    total += len;
    for (std::uint32_t v : e) fr.edge[v] += len, ++count[v];
  }
  fr.mean_edge = adj.edges.empty() ? 0 : total / static_cast<double>(adj.edges.size());
  for (size_t v = 0; v < nv; ++v) fr.edge[v] = count[v] > 0 ? fr.edge[v] / count[v] : fr.mean_edge;
  fr.nearest_node.assign(nv, -1);
  fr.on_curve.assign(nv, 0);
  fr.near_curve.assign(nv, 0);
  const double reach = kNodeReach * fr.mean_edge;
  for (size_t v = 0; v < nv; ++v) {
    double best = reach;
    for (size_t k = 0; k < nodes.size(); ++k) {
      const double d = (mesh.positions[v] - nodes[k]).norm();
      if (d <= best) best = d, fr.nearest_node[v] = static_cast<int>(k);
    }
  }
  for (const MeshCurve& c : mesh.curves)
    for (std::uint32_t v : c.vertices) fr.on_curve[v] = 1, fr.near_curve[v] = 1;
  // The ring around a curve: ∇F is small there too.
  for (size_t v = 0; v < nv; ++v) {
    if (!fr.on_curve[v]) continue;
    for (std::uint32_t q = adj.neighbor_offsets[v]; q < adj.neighbor_offsets[v + 1]; ++q)
      fr.near_curve[adj.neighbors[q]] = 1;
  }
  return fr;
}

// Each old singular point's partner among the new ones: the nearest, one to one. Empty when
// some old point has none within `reach` (then the points did not just move).
std::vector<int> match_points(const std::vector<Vec3>& from, const std::vector<Vec3>& to,
                              double reach) {
  std::vector<int> match(from.size(), -1);
  std::vector<std::uint8_t> taken(to.size(), 0);
  for (size_t a = 0; a < from.size(); ++a) {
    double best = reach;
    for (size_t b = 0; b < to.size(); ++b) {
      const double d = (from[a] - to[b]).norm();
      if (!taken[b] && d <= best) best = d, match[a] = static_cast<int>(b);
    }
    if (match[a] < 0) return {};
    taken[static_cast<size_t>(match[a])] = 1;
  }
  return match;
}

// Newton's method on ∇F = 0 from p (a vertex of a singular curve on the old surface): the
// least-squares steps of critical_step() slide it across the curve, not along it.
bool project_onto_singular_curve(Evaluator& ev, Vec3& p, double tolerance) {
  for (int it = 0; it < kCurveNewtonSteps; ++it) {
    const FieldSample s = ev.sample(p, Derivatives::kHessian);
    if (!std::isfinite(s.value) || !s.gradient.allFinite()) return false;
    const CriticalStep c = critical_step(s.gradient, s.hessian);
    if (!c.step.allFinite()) return false;
    p -= c.step;
    if (c.step.norm() < tolerance)
      return std::abs(ev.value(p)) < 1e3 * tolerance * (1 + s.hessian.norm());
  }
  return false;
}

}  // namespace

std::string_view to_string(CarryFailure failure) {
  switch (failure) {
    case CarryFailure::kNone:
      return "carried";
    case CarryFailure::kEquation:
      return "equation";
    case CarryFailure::kSingularSet:
      return "singular set";
    case CarryFailure::kProjection:
      return "projection";
    case CarryFailure::kLongMove:
      return "long move";
    case CarryFailure::kClip:
      return "clip";
    case CarryFailure::kFlipped:
      return "flipped";
    case CarryFailure::kAngle:
      return "angle";
    case CarryFailure::kResidual:
      return "residual";
    case CarryFailure::kStopped:
      return "stopped";
  }
  return "?";
}

namespace {

// The old and the new singular points, matched, and the vertex that sits on each old one.
struct NodeMatch {
  const CarrySingularSet& old_set;
  const CarrySingularSet& new_set;
  std::vector<int> match;    // old point k -> new point match[k]
  std::vector<int> node_of;  // vertex -> old point, -1 for none

  const Vec3& new_point_of_vertex(size_t v) const {
    return new_set.points[static_cast<size_t>(match[static_cast<size_t>(node_of[v])])];
  }
};

// The vertex at each old singular point (within 1e-3 edges).
long long find_node_vertices(const Mesh& mesh, double h, NodeMatch& nodes) {
  const size_t nv = mesh.vertex_count();
  nodes.node_of.assign(nv, -1);
  long long found = 0;
  for (size_t k = 0; k < nodes.old_set.points.size(); ++k) {
    size_t best = nv;
    double best_d = 1e-3 * h;
    for (size_t v = 0; v < nv; ++v) {
      const double d = (mesh.positions[v] - nodes.old_set.points[k]).norm();
      if (d <= best_d) best_d = d, best = v;
    }
    if (best < nv) nodes.node_of[best] = static_cast<int>(k), ++found;
  }
  return found;
}

// The first vertex that could not be moved, and why.
struct MoveFailure {
  CarryFailure why = CarryFailure::kNone;
  long long vertex = -1;
};

// Moves every vertex onto the new surface: a node vertex to its partner, a curve vertex onto
// the new curve by Newton's method, any other by the first-order predictor (the parameter term
// F_q·Δq, blended into the nearest node's own move near a node) then projected onto F = 0 (onto
// the clip curve for a boundary vertex). `moved`: each vertex's move.
MoveFailure move_vertices(const Mesh& mesh, Mesh& out, const Surface& from, const Surface& to,
                          const CarryOptions& options, const VertexFrame& fr,
                          const NodeMatch& nodes, detail::EvaluatorPool& old_pool,
                          detail::EvaluatorPool& new_pool, int workers,
                          std::vector<double>& moved) {
  const size_t nv = mesh.vertex_count();
  const double h = fr.mean_edge;
  const std::vector<double>& q0 = from.field.parameter_values();
  const std::vector<double>& q1 = to.field.parameter_values();
  std::vector<double> dq(q0.size());
  for (size_t k = 0; k < q0.size(); ++k) dq[k] = q1[k] - q0[k];
  std::atomic<int> failure{static_cast<int>(CarryFailure::kNone)};
  std::atomic<long long> failed_vertex{-1};
  moved.assign(nv, 0);
  const double tolerance = kProjectionTolerance * h;
  const bool has_clip = !to.clip.is_empty_spec();
  detail::ExceptionTrap trap;
  const long long n = static_cast<long long>(nv);
#pragma omp parallel for num_threads(workers) schedule(dynamic, 256)
  for (long long vv = 0; vv < n; ++vv)
    trap.run([&] {
      if (failure.load(std::memory_order_relaxed) != 0) return;
      const size_t v = static_cast<size_t>(vv);
      const Vec3 start = mesh.positions[v];
      Vec3 p = start, predicted = start;
      const double limit = options.max_move_edges * fr.edge[v];
      auto fail = [&](CarryFailure why) {
        int none = 0;
        if (failure.compare_exchange_strong(none, static_cast<int>(why))) failed_vertex = vv;
      };
      const int nearest = fr.nearest_node[v];
      if (nodes.node_of[v] >= 0) {
        p = nodes.new_point_of_vertex(v);
      } else if (fr.on_curve[v]) {
        if (!project_onto_singular_curve(new_pool.local(), p, tolerance))
          return fail(CarryFailure::kProjection);
      } else {
        // The predictor: the parameter term, blended into the node's own move within
        // kNodeReach edges of a node (fully the node's within half of that), so that
        // neighbours do not get moves of a different kind.
        double w = 0;
        Vec3 node_move = Vec3::Zero();
        if (nearest >= 0) {
          const size_t k = static_cast<size_t>(nearest);
          node_move =
              nodes.new_set.points[static_cast<size_t>(nodes.match[k])] - nodes.old_set.points[k];
          const double d = (start - nodes.old_set.points[k]).norm(), reach = kNodeReach * h;
          w = std::clamp(2 * (reach - d) / reach, 0.0, 1.0);
        }
        Vec3 term = Vec3::Zero();
        if (w < 1) {
          const FieldSample s = old_pool.local().sample(start, Derivatives::kParameters);
          double fq = 0;
          for (size_t k = 0; k < dq.size() && k < s.dq.size(); ++k) fq += s.dq[k] * dq[k];
          const double g2 = s.gradient.squaredNorm();
          if (g2 > 0 && std::isfinite(fq) && std::isfinite(g2)) term = -(fq / g2) * s.gradient;
        }
        p += w * node_move + (1 - w) * term;
        predicted = p;
        const bool on_clip = out.is_boundary.size() == nv && out.is_boundary[v] && has_clip &&
                             std::abs(from.clip.value(start)) <= 1e-7 * (1 + start.norm());
        if (on_clip) {
          p = project_onto_clip_curve(new_pool.local(), to.clip, p, limit);
          Vec3 g;
          const double f = new_pool.local().value_gradient(p, g);
          if (!has_residual(f, g.norm()) || residual(f, g.norm()) > options.max_residual_edges * h)
            return fail(CarryFailure::kClip);
        } else if (!project_onto_surface(new_pool.local(), p, tolerance, 2 * limit)) {
          return fail(CarryFailure::kProjection);
        }
      }
      // The prediction is first order: where Newton has to correct it by more than a fraction
      // of an edge, the surface did not just move here (a new sheet, a pinch) or moved too far.
      moved[v] = (p - start).norm();
      if (!((p - predicted).norm() <= limit) && nodes.node_of[v] < 0)
        return fail(CarryFailure::kLongMove);
      if (has_clip && !(out.is_boundary.size() == nv && out.is_boundary[v]) &&
          to.clip.value(p) > 1e-9 * (1 + p.norm()))
        return fail(CarryFailure::kClip);
      out.positions[v] = p;
    });
  trap.rethrow();
  return {static_cast<CarryFailure>(failure.load()), failed_vertex.load()};
}

// A few improver steps on the new surface, then its final projection; node vertices stay on
// their nodes. False when stopped.
bool improve_carried(Mesh& out, const Surface& to, const CarryOptions& options, int workers,
                     const NodeMatch& nodes, ImproveStats& stats, std::stop_token stop) {
  ImproveOptions improve = options.improve;
  improve.threads = workers;  // its final normals too: not every core for a small mesh
  improve.max_steps = options.improve_steps;
  // Edge flips are the dearest part of a step (a serial pass over every edge): one pass undoes
  // the stretching of a small move; the springs do the rest.
  improve.flip_steps = std::min(improve.flip_steps, 1);
  MeshImprover improver(std::move(out), to, improve);
  for (int i = 0; i < options.improve_steps && !improver.converged() && !stop.stop_requested(); ++i)
    improver.step();
  if (stop.stop_requested()) return false;
  improver.finish();
  stats = improver.stats();
  out = improver.take_mesh();
  // The improver holds the singular points it finds itself; one it missed may have let its
  // vertex drift. Node vertices stay on their nodes (the checks see any harm).
  bool node_moved = false;
  for (size_t v = 0; v < nodes.node_of.size(); ++v) {
    if (nodes.node_of[v] < 0) continue;
    const Vec3& node = nodes.new_point_of_vertex(v);
    node_moved |= out.positions[v] != node;
    out.positions[v] = node;
  }
  if (node_moved) compute_field_normals(out, to, workers);
  return true;
}

// The checks away from the singular set (its neighbourhood as the new points give it): the
// largest residual, triangles facing against ∇F and the smallest angle, before and after.
struct CarryChecks {
  double worst_residual = 0;
  long long flipped_triangles = 0;
  double smallest_before = 180, smallest_after = 180;
  bool any_checked = false;
};

CarryChecks check_carried(const Mesh& mesh, const Mesh& out, const std::vector<Vec3>& new_points,
                          detail::EvaluatorPool& pool, int workers) {
  CarryChecks c;
  const VertexFrame fr = vertex_frame(out, new_points);
  std::vector<double> f;
  std::vector<Vec3> g;
  detail::values_gradients(pool, workers, out.positions, f, g);
  // As measure_quality() does: whatever lies within kNodeReach mean edges of a singular point.
  auto near_point = [&](const Vec3& p) {
    for (const Vec3& q : new_points)
      if ((p - q).norm() < kNodeReach * fr.mean_edge) return true;
    return false;
  };
  for (size_t v = 0; v < out.vertex_count(); ++v) {
    if (fr.near_curve[v] || near_point(out.positions[v])) continue;
    c.worst_residual = std::max(c.worst_residual, residual(f[v], g[v].norm()));
  }
  std::vector<Vec3> centroids;
  std::vector<std::uint32_t> checked;
  for (size_t t = 0; t < out.triangles.size(); ++t) {
    const auto& tri = out.triangles[t];
    if (fr.near_curve[tri[0]] || fr.near_curve[tri[1]] || fr.near_curve[tri[2]]) continue;
    const Vec3 &a = out.positions[tri[0]], &b = out.positions[tri[1]], &d = out.positions[tri[2]];
    if (near_point((a + b + d) / 3)) continue;
    centroids.push_back((a + b + d) / 3);
    checked.push_back(static_cast<std::uint32_t>(t));
    c.smallest_after = std::min(c.smallest_after, triangle_min_angle_deg(a, b, d));
    c.smallest_before = std::min(
        c.smallest_before, triangle_min_angle_deg(mesh.positions[tri[0]], mesh.positions[tri[1]],
                                                  mesh.positions[tri[2]]));
  }
  std::vector<double> fc;
  std::vector<Vec3> gc;
  detail::values_gradients(pool, workers, centroids, fc, gc);
  for (size_t i = 0; i < checked.size(); ++i) {
    const auto& tri = out.triangles[checked[i]];
    const Vec3 normal =
        detail::area_normal(out.positions[tri[0]], out.positions[tri[1]], out.positions[tri[2]]);
    if (gc[i].allFinite() && normal.dot(gc[i]) < 0) ++c.flipped_triangles;
  }
  c.any_checked = !checked.empty();
  return c;
}

}  // namespace

CarryResult carry_mesh(const Mesh& mesh, const Surface& from, const Surface& to,
                       const CarryOptions& options, std::stop_token stop) {
  const auto t0 = Clock::now();
  check_options(options);
  const size_t nv = mesh.vertex_count();
  for (const auto& t : mesh.triangles)
    for (std::uint32_t v : t)
      if (v >= nv)
        throw InvalidArgument("mesh", fmt::format("vertex {}", v), "refers to a missing vertex");
  if (from.field.source() != to.field.source() ||
      from.field.parameter_names() != to.field.parameter_names())
    return failed(CarryFailure::kEquation, "another equation", t0);
  from.field.require_parameters();
  to.field.require_parameters();
  if (mesh.empty()) return failed(CarryFailure::kProjection, "no mesh to carry", t0);

  // The singular set must only have moved.
  const CarrySingularSet old_set = options.from_singular && !from.singular_points_fn
                                       ? *options.from_singular
                                       : singular_info(from, options);
  const CarrySingularSet new_set = singular_info(to, options);
  // Failures from here on still hand back the new singular set (for the next carry's options).
  auto failed_after = [&](CarryFailure why, std::string reason) {
    CarryResult bad = failed(why, std::move(reason), t0);
    bad.singular = new_set;
    return bad;
  };
  if (old_set.points.size() != new_set.points.size())
    return failed_after(
        CarryFailure::kSingularSet,
        fmt::format("singular points: {} → {}", old_set.points.size(), new_set.points.size()));
  if (old_set.curves != new_set.curves)
    return failed_after(CarryFailure::kSingularSet,
                        fmt::format("singular curves: {} → {}", old_set.curves, new_set.curves));
  const VertexFrame fr = vertex_frame(mesh, old_set.points);
  const double h = fr.mean_edge;
  NodeMatch nodes{old_set,
                  new_set,
                  match_points(old_set.points, new_set.points, options.max_move_edges * h * 4),
                  {}};
  if (nodes.match.size() != old_set.points.size())
    return failed_after(CarryFailure::kSingularSet, "a singular point jumped");
  if (stop.stop_requested()) return failed_after(CarryFailure::kStopped, "stopped");

  CarryResult r;
  r.singular = new_set;
  r.node_vertices = find_node_vertices(mesh, h, nodes);
  Mesh out = mesh;
  const int workers = detail::improver_workers(options.threads, nv);
  detail::EvaluatorPool old_pool(from.field, workers), new_pool(to.field, workers);
  std::vector<double> moved;
  const MoveFailure failure =
      move_vertices(mesh, out, from, to, options, fr, nodes, old_pool, new_pool, workers, moved);
  if (failure.why != CarryFailure::kNone) {
    const char* what = failure.why == CarryFailure::kLongMove ? "was corrected by more than {} edge"
                       : failure.why == CarryFailure::kClip   ? "left the clip curve"
                                                              : "found no surface nearby";
    return failed_after(
        failure.why,
        fmt::format(fmt::runtime(fmt::format("a vertex {}", what)), options.max_move_edges) +
            (failure.vertex >= 0 ? fmt::format(" (vertex {})", failure.vertex) : std::string()));
  }
  for (size_t v = 0; v < nv; ++v)
    r.max_move_edges = std::max(r.max_move_edges, moved[v] / fr.edge[v]);
  if (stop.stop_requested()) return failed_after(CarryFailure::kStopped, "stopped");
  if (!improve_carried(out, to, options, workers, nodes, r.improve, stop))
    return failed_after(CarryFailure::kStopped, "stopped");

  const CarryChecks c = check_carried(mesh, out, new_set.points, new_pool, workers);
  r.max_residual = c.worst_residual;
  r.flipped_triangles = c.flipped_triangles;
  r.smallest_angle_deg = c.any_checked ? c.smallest_after : 0;
  r.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  auto refuse = [&](CarryFailure why, std::string reason) {
    CarryResult bad = r;
    bad.failure = why;
    bad.reason = std::move(reason);
    return bad;
  };
  if (r.flipped_triangles > 0)
    return refuse(CarryFailure::kFlipped,
                  fmt::format("{} triangles face against ∇F", r.flipped_triangles));
  if (c.smallest_after < options.min_angle_deg && c.smallest_after < c.smallest_before)
    return refuse(CarryFailure::kAngle, fmt::format("smallest angle {:.2g}° (was {:.2g}°)",
                                                    c.smallest_after, c.smallest_before));
  if (!(c.worst_residual <= options.max_residual_edges * h))
    return refuse(CarryFailure::kResidual,
                  fmt::format("|F|/|∇F| = {:.2g} edge lengths left",
                              h > 0 ? c.worst_residual / h : c.worst_residual));
  r.mesh = std::move(out);
  return r;
}

}  // namespace zeroset
