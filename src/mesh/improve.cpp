#include "zeroset/mesh/improve.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <fmt/core.h>

#include "mesh_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/error.h"
#include "zeroset/mesh/adjacency.h"
#include "zeroset/mesh/mesh_ops.h"
#include "zeroset/surface/analysis.h"

namespace zeroset {
namespace {

using Clock = std::chrono::steady_clock;
using detail::kNone;
// Radians of Delaunay excess (and mean-ratio gain) an edge flip needs.
constexpr double kFlipMargin = 0.05;

enum Mode : std::uint8_t { kFree = 0, kHeld = 1, kOnCurve = 2 };
// |∇F|² below this × grad_ref² marks a vertex that has reached a singular curve.
constexpr double kOnSingularCurve = 1e-4;
// A vertex keeps the inertia of its last move (ImproveOptions::inertia) only where none of its
// springs is stiffer than this × κ_0: flat parts away from creases and singular points.
constexpr double kFlatSpring = 1.5;

}  // namespace

struct MeshImprover::State {
  Mesh mesh;
  Surface surface;
  ImproveOptions opt;
  int workers = 1;
  detail::EvaluatorPool pool;
  ImproveStats stats;
  bool converged = false;
  bool finished = false;

  // Connectivity with fixed capacity per vertex, kept up to date by edge flips.
  int cap = 0;
  std::vector<std::uint32_t> nbr, nbr_count;    // neighbours
  std::vector<std::uint32_t> vtri, vtri_count;  // incident triangles

  std::vector<std::uint8_t> mode;
  std::vector<std::uint8_t> near_curve;  // within three rings of a singular curve
  std::vector<double> f, beta, step_to_critical;
  std::vector<Vec3> grad, unit;  // ∇F and ∇F/|∇F| (zero where ∇F vanishes)
  std::vector<Vec3> move;
  std::vector<double> scale;
  // The positions before the last apply_moves: a vertex that went where F or ∇F is not finite
  // goes back there (evaluate_field).
  std::vector<Vec3> previous;
  double grad_ref = 1;  // median |∇F|
  double mean_edge = 0;

  State(Mesh m, const Surface& s, const ImproveOptions& o)
      : mesh(std::move(m)),
        surface(s),
        opt(o),
        workers(detail::improver_workers(o.threads, mesh.positions.size())),
        pool(s.field, workers) {}

  size_t nv() const { return mesh.positions.size(); }
  std::uint32_t* nb(std::uint32_t v) {
    return &nbr[static_cast<size_t>(v) * static_cast<size_t>(cap)];
  }
  std::uint32_t* vt(std::uint32_t v) {
    return &vtri[static_cast<size_t>(v) * static_cast<size_t>(cap)];
  }

  void build_connectivity() {
    const MeshAdjacency adj = build_adjacency(mesh);
    const VertexTriangles vtris = build_vertex_triangles(nv(), mesh.triangles);
    size_t maxdeg = 0;
    for (size_t v = 0; v < nv(); ++v)
      maxdeg = std::max({maxdeg, adj.valence(static_cast<std::uint32_t>(v)),
                         vtris.count(static_cast<std::uint32_t>(v))});
    cap = static_cast<int>(std::max<size_t>(16, maxdeg + 4));
    nbr.assign(nv() * static_cast<size_t>(cap), kNone);
    vtri.assign(nbr.size(), kNone);
    nbr_count.assign(nv(), 0);
    vtri_count.assign(nv(), 0);
    for (size_t v = 0; v < nv(); ++v)
      for (std::uint32_t q = adj.neighbor_offsets[v]; q < adj.neighbor_offsets[v + 1]; ++q)
        nb(static_cast<std::uint32_t>(v))[nbr_count[v]++] = adj.neighbors[q];
    for (size_t v = 0; v < nv(); ++v)
      for (std::uint32_t t : vtris.of(static_cast<std::uint32_t>(v)))
        vt(static_cast<std::uint32_t>(v))[vtri_count[v]++] = t;
    // Vertices on the mesh border that are not on the clip would be pulled inwards: hold them.
    for (size_t e = 0; e < adj.edges.size(); ++e)
      if (adj.edge_triangle_count[e] != 2)
        for (std::uint32_t v : adj.edges[e])
          if (mode[v] == kFree) mode[v] = kHeld;
  }

  void init_modes() {
    mode.assign(nv(), kFree);
    if (mesh.is_boundary.size() != nv()) mesh.is_boundary.assign(nv(), 0);
    for (size_t v = 0; v < nv(); ++v) {
      if (!mesh.is_boundary[v]) continue;
      const Vec3& p = mesh.positions[v];
      const bool on_clip =
          !surface.clip.is_empty_spec() && std::abs(surface.clip.value(p)) <= 1e-7 * (1 + p.norm());
      mode[v] = opt.boundary == BoundaryMode::kConstrained && on_clip ? kOnCurve : kHeld;
    }
    // Vertices on singular curves lie on them already (mesh_crossings) and stay there.
    for (const MeshCurve& c : mesh.curves)
      for (std::uint32_t v : c.vertices) mode[v] = kHeld;
  }

  // Vertices within three rings of a singular curve: Newton on ∇F = 0 from them lands on the
  // curve, whose points are vertices already.
  void mark_near_curves() {
    near_curve.assign(nv(), 0);
    std::vector<std::uint32_t> front;
    for (const MeshCurve& c : mesh.curves)
      for (std::uint32_t v : c.vertices)
        if (!near_curve[v]) near_curve[v] = 1, front.push_back(v);
    for (int ring = 0; ring < 3 && !front.empty(); ++ring) {
      std::vector<std::uint32_t> next;
      for (std::uint32_t v : front)
        for (std::uint32_t k = 0; k < nbr_count[v]; ++k) {
          const std::uint32_t w = nb(v)[k];
          if (!near_curve[w]) near_curve[w] = 1, next.push_back(w);
        }
      front = std::move(next);
    }
  }

  // Whether a move from `from` to `to` keeps the vertex in the clip: G may not grow beyond
  // the boundary (vertices on the clip curve stay within rounding of it).
  bool stays_inside(const Vec3& from, const Vec3& to) const {
    if (!to.allFinite()) return false;
    if (surface.clip.is_empty_spec()) return true;
    const double g = surface.clip.value(to);
    return g <= 0 || g <= std::max(surface.clip.value(from), 0.0) + 1e-12 * (1 + to.norm());
  }

  void evaluate_field() {
    detail::values_gradients(pool, workers, mesh.positions, f, grad);
    // A vertex that moved onto a point where F or ∇F is not finite (a pole, a NaN region)
    // goes back to where it was: the move is refused. Rare, so serial.
    if (previous.size() == nv())
      for (size_t v = 0; v < nv(); ++v) {
        if (std::isfinite(f[v]) && grad[v].allFinite()) continue;
        if (previous[v] == mesh.positions[v]) continue;
        mesh.positions[v] = previous[v];
        f[v] = pool.local().value_gradient(mesh.positions[v], grad[v]);
        ++stats.refused_moves;
      }
    unit.resize(nv());
    for (size_t v = 0; v < nv(); ++v) {
      const double len = grad[v].norm();
      unit[v] = len > 0 && std::isfinite(len) ? Vec3(grad[v] / len) : Vec3::Zero();
    }
    std::vector<double> lens;
    lens.reserve(nv());
    for (size_t v = 0; v < nv(); ++v)
      if (std::isfinite(grad[v].norm())) lens.push_back(grad[v].norm());
    if (!lens.empty()) {
      std::nth_element(lens.begin(), lens.begin() + static_cast<long>(lens.size() / 2), lens.end());
      grad_ref = lens[lens.size() / 2] > 0 ? lens[lens.size() / 2] : 1.0;
    }
  }

  void update_mean_edge() {
    mean_edge = detail::improver_mean_edge(mesh.positions, nbr, nbr_count, cap, workers);
  }

  // β of docs/algorithms.md B.3 and C.1 at every vertex, and the Newton step length towards ∇F = 0.
  void update_singularity_estimates() {
    const long long n = static_cast<long long>(nv());
    beta.assign(nv(), 1.0);
    step_to_critical.assign(nv(), std::numeric_limits<double>::infinity());
    const double gamma = opt.singularity_scale * mean_edge;
    detail::ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(dynamic, 256)
    for (long long v = 0; v < n; ++v)
      trap.run([&] {
        const FieldSample s =
            pool.local().sample(mesh.positions[static_cast<size_t>(v)], Derivatives::kHessian);
        const double r = pseudo_inverse_step(s.gradient, s.hessian).norm();
        step_to_critical[static_cast<size_t>(v)] = r;
        beta[static_cast<size_t>(v)] =
            gamma > 0 && std::isfinite(r) ? std::min(r / gamma, 1.0) : 1.0;
      });
    trap.rethrow();
  }

  // Newton on ∇F = 0 from vertices whose step to a critical point is shorter than an edge.
  void find_singular_points() {
    std::vector<std::uint32_t> cand;
    for (size_t v = 0; v < nv(); ++v)
      if (mode[v] == kFree && !near_curve[v] && step_to_critical[v] < mean_edge)
        cand.push_back(static_cast<std::uint32_t>(v));
    const long long nc = static_cast<long long>(cand.size());
    std::vector<Vec3> found(cand.size());
    std::vector<std::uint8_t> ok(cand.size(), 0);
    detail::ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(dynamic, 4)
    for (long long c = 0; c < nc; ++c)
      trap.run([&] {
        // Any critical point, singular curves too (min_conditioning 0).
        const auto x = find_critical_point(
            pool.local(), mesh.positions[cand[static_cast<size_t>(c)]],
            {.iterations = 30, .reach = 2 * mean_edge, .tolerance = 1e-13, .length = 1});
        if (!x) return;
        if (x->gradient.norm() <= 1e-8 * grad_ref &&
            std::abs(x->value) <= 1e-8 * grad_ref * mean_edge &&
            (surface.clip.is_empty_spec() || surface.clip.contains(x->point))) {
          found[static_cast<size_t>(c)] = x->point;
          ok[static_cast<size_t>(c)] = 1;
        }
      });
    trap.rethrow();
    const double same = 1e-3 * mean_edge;
    for (size_t c = 0; c < cand.size(); ++c) {
      if (!ok[c]) continue;
      const Vec3 q = found[c];
      auto known = [&](const Vec3& p) { return (p - q).norm() < same; };
      if (std::any_of(stats.singular_points.begin(), stats.singular_points.end(), known)) continue;
      // The nearest free vertex among the candidates and their neighbours.
      std::uint32_t best = kNone;
      double best_d = std::numeric_limits<double>::infinity();
      auto consider = [&](std::uint32_t v) {
        if (mode[v] != kFree) return;
        const double d = (mesh.positions[v] - q).norm();
        if (d < best_d) best_d = d, best = v;
      };
      for (std::uint32_t v : cand) {
        consider(v);
        for (std::uint32_t k = 0; k < nbr_count[v]; ++k) consider(nb(v)[k]);
      }
      if (best == kNone || best_d > 2 * mean_edge) continue;
      if (move_single_vertex(best, q)) {
        mode[best] = kHeld;
        stats.singular_points.push_back(q);
      }
    }
  }

  // The flip guard for one triangle: would moving its corners to `to` turn it over against
  // ∇F (where it agreed before), fold it by more than 90°, or shrink it to nothing?
  bool triangle_bad(std::uint32_t t, const Vec3* to) const {
    const auto& tri = mesh.triangles[t];
    const Vec3& a = mesh.positions[tri[0]];
    const Vec3& b = mesh.positions[tri[1]];
    const Vec3& c = mesh.positions[tri[2]];
    const Vec3 n0 = detail::area_normal(a, b, c);
    const Vec3 n1 = detail::area_normal(to[0], to[1], to[2]);
    if (!(n1.dot(n0) > 0)) return true;
    const double min_area2 = opt.min_area_fraction * std::sqrt(3.0) / 2 * mean_edge * mean_edge;
    if (n1.norm() < min_area2 && n1.norm() < n0.norm()) return true;
    const Vec3 ref = unit[tri[0]] + unit[tri[1]] + unit[tri[2]];
    return n0.dot(ref) > 0 && !(n1.dot(ref) > 0);
  }

  Vec3 target(std::uint32_t v) const {
    Vec3 p = mesh.positions[v] + scale[v] * move[v];
    if (mode[v] == kOnCurve) p = snap_to_clip(surface.clip, p);
    return p;
  }

  // Moves one vertex to q, halving the move while a triangle objects. True when it got there.
  bool move_single_vertex(std::uint32_t v, const Vec3& q) {
    const Vec3 from = mesh.positions[v];
    for (int attempt = 0; attempt < 8; ++attempt) {
      const double s = std::ldexp(1.0, -attempt);
      const Vec3 to = from + s * (q - from);
      bool bad = false;
      for (std::uint32_t k = 0; k < vtri_count[v] && !bad; ++k) {
        const std::uint32_t t = vt(v)[k];
        Vec3 corners[3];
        for (int c = 0; c < 3; ++c) {
          const std::uint32_t w = mesh.triangles[t][static_cast<size_t>(c)];
          corners[c] = w == v ? to : mesh.positions[w];
        }
        bad = triangle_bad(t, corners);
      }
      if (!bad) {
        if (!stays_inside(from, to)) {
          ++stats.refused_moves;
          return false;
        }
        mesh.positions[v] = to;
        return attempt == 0;
      }
    }
    return false;
  }

  // Applies `move` under the flip guard; returns the largest move made. The first round checks
  // every triangle with a moving corner, later rounds only those around shortened moves.
  double apply_moves() {
    const long long n = static_cast<long long>(nv());
    scale.assign(nv(), 1.0);
    std::vector<std::uint32_t> check;
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
      for (std::uint32_t v : mesh.triangles[t])
        if (move[v].squaredNorm() > 0) {
          check.push_back(t);
          break;
        }
    std::vector<std::uint8_t> touched(nv(), 0);
    // Where each vertex would go, kept up to date as moves are shortened (each triangle
    // check would otherwise recompute three of them).
    std::vector<Vec3> dest(nv());
    detail::ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(static)
    for (long long v = 0; v < n; ++v)
      trap.run([&] { dest[static_cast<size_t>(v)] = target(static_cast<std::uint32_t>(v)); });
    trap.rethrow();
    for (int round = 0; !check.empty(); ++round) {
      std::vector<std::uint32_t> bad;
      const long long nc = static_cast<long long>(check.size());
#pragma omp parallel num_threads(workers) if (nc > 4096)
      {
        std::vector<std::uint32_t> local;
#pragma omp for schedule(static) nowait
        for (long long c = 0; c < nc; ++c)
          trap.run([&] {
            const std::uint32_t t = check[static_cast<size_t>(c)];
            const auto& tri = mesh.triangles[t];
            const Vec3 to[3] = {dest[tri[0]], dest[tri[1]], dest[tri[2]]};
            if (triangle_bad(t, to)) local.push_back(t);
          });
#pragma omp critical
        trap.run([&] { bad.insert(bad.end(), local.begin(), local.end()); });
      }
      trap.rethrow();
      if (bad.empty()) break;
      std::sort(bad.begin(), bad.end());  // the same result whatever the thread timing
      const bool cancel = round >= 6;
      std::vector<std::uint32_t> changed;
      for (std::uint32_t t : bad)
        for (std::uint32_t v : mesh.triangles[t]) {
          if (touched[v] || scale[v] == 0 || move[v].squaredNorm() == 0) continue;
          touched[v] = 1;
          changed.push_back(v);
          if (cancel) {
            scale[v] = 0;
            ++stats.cancelled_moves;
          } else {
            scale[v] *= 0.5;
            ++stats.shortened_moves;
          }
          dest[v] = target(v);
        }
      check.clear();
      for (std::uint32_t v : changed) {
        touched[v] = 0;
        for (std::uint32_t k = 0; k < vtri_count[v]; ++k) check.push_back(vt(v)[k]);
      }
      std::sort(check.begin(), check.end());
      check.erase(std::unique(check.begin(), check.end()), check.end());
    }
    double max_move = 0;
    long long outside = 0;
    std::vector<Vec3> next(nv());
#pragma omp parallel for num_threads(workers) schedule(static) reduction(max : max_move) \
    reduction(+ : outside)
    for (long long v = 0; v < n; ++v)
      trap.run([&] {
        const std::uint32_t u = static_cast<std::uint32_t>(v);
        const Vec3& p = mesh.positions[u];
        bool go = scale[u] > 0;
        if (go && move[u].squaredNorm() > 0 && !stays_inside(p, dest[u])) go = false, ++outside;
        next[u] = go ? dest[u] : p;
        max_move = std::max(max_move, (next[u] - p).norm());
      });
    trap.rethrow();
    stats.refused_moves += outside;
    previous = std::move(mesh.positions);
    mesh.positions = std::move(next);
    return max_move;
  }

  // Desired velocities from the springs, made tangent to F = 0 (and G = 0 on the boundary).
  void compute_moves() {
    const long long n = static_cast<long long>(nv());
    move.assign(nv(), Vec3::Zero());
    const bool coast = opt.inertia > 0 && previous.size() == nv();
    const double eps2 = 1e-6 * grad_ref * grad_ref;
    const double phi = opt.feedback;
    detail::ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(static)
    for (long long vv = 0; vv < n; ++vv)
      trap.run([&] {
        const std::uint32_t v = static_cast<std::uint32_t>(vv);
        if (mode[v] == kHeld || nbr_count[v] == 0) return;
        const Vec3& p = mesh.positions[v];
        double wsum = 0, stiffest = 0, shortest = std::numeric_limits<double>::infinity();
        Vec3 wp = Vec3::Zero();
        // A vertex on the clip curve is pulled by its neighbours along the curve only: the
        // interior's pull would turn the whole mesh about the clip's axis wherever that is a
        // motion of zero energy (a disk in a sphere), a drift the springs never stop.
        int along = 0;
        if (mode[v] == kOnCurve)
          for (std::uint32_t k = 0; k < nbr_count[v]; ++k) along += mode[nb(v)[k]] == kOnCurve;
        for (std::uint32_t k = 0; k < nbr_count[v]; ++k) {
          const std::uint32_t w = nb(v)[k];
          if (along >= 2 && mode[w] != kOnCurve) {
            shortest = std::min(shortest, (mesh.positions[w] - p).norm());
            continue;
          }
          double kappa = opt.spring_base;
          // A singular curve's vertices are placed already at the mesh's spacing: no estimator
          // pulls the sheets' vertices into it (∇F = 0 there, and its sheets turn every way).
          const bool by_curve = near_curve[v] || near_curve[w];
          if (opt.use_curvature && !(by_curve && (unit[v].isZero() || unit[w].isZero())))
            kappa += opt.curvature_weight * (1 - unit[v].dot(unit[w]));
          if (opt.use_singularity && !beta.empty() && !by_curve)
            kappa += opt.singularity_weight * (1 - std::min(beta[v], beta[w]));
          wsum += kappa;
          stiffest = std::max(stiffest, kappa);
          wp += kappa * mesh.positions[w];
          shortest = std::min(shortest, (mesh.positions[w] - p).norm());
        }
        const Vec3 P = opt.relaxation * (wp / wsum - p);
        const Vec3& g = grad[v];
        Vec3 vel;
        if (!std::isfinite(f[v]) || !g.allFinite()) return;
        // A sheet's vertex that has come onto a singular curve (∇F all but zero, as at a pinch
        // point, where the sheets close up on the curve) has no tangent plane to slide in: the
        // springs alone would push it to and fro along the curve. It stays where it is.
        if (near_curve[v] && g.squaredNorm() < kOnSingularCurve * grad_ref * grad_ref) return;
        if (mode[v] == kFree && coast && !near_curve[v] &&
            stiffest <= kFlatSpring * opt.spring_base) {
          // Heavy-ball momentum on the tangential part only (docs/algorithms.md, C.2): the last
          // move, made tangent, carried over; the Newton part towards F = 0 stays as it is.
          const double gg = g.dot(g) + eps2;
          Vec3 last = p - previous[v];
          last -= (g.dot(last) / gg) * g;
          vel = P - (g.dot(P) / gg) * g + opt.inertia * last - (phi * f[v] / gg) * g;
        } else if (mode[v] == kFree) {
          vel = P - ((g.dot(P) + phi * f[v]) / (g.dot(g) + eps2)) * g;
        } else {  // on the clip curve: both constraints (paper §4.2)
          Vec3 gg;
          const double gv = surface.clip.value_gradient(p, gg);
          double a = g.dot(g) + eps2, b = g.dot(gg), d = gg.dot(gg);
          d += 1e-12 * d + 1e-300;
          const double r0 = g.dot(P) + phi * f[v], r1 = gg.dot(P) + phi * gv;
          const double det = a * d - b * b;
          if (det > 1e-9 * a * d) {
            const double l0 = (d * r0 - b * r1) / det, l1 = (a * r1 - b * r0) / det;
            vel = P - l0 * g - l1 * gg;
          } else {  // F = 0 touches the clip: keep only the clip constraint
            vel = P - (r1 / d) * gg;
          }
        }
        const double len = vel.norm(), limit = opt.max_move_fraction * shortest;
        if (len > limit) vel *= limit / len;
        if (vel.allFinite()) move[v] = vel;
      });
    trap.rethrow();
  }

  // Delaunay flips between nearly coplanar triangles (serial; keeps the connectivity arrays).
  long long flip_edges() {
    const double cos_max = std::cos(opt.flip_max_dihedral_deg * std::numbers::pi / 180);
    const double min_area2 = opt.min_area_fraction * std::sqrt(3.0) / 2 * mean_edge * mean_edge;
    auto& T = mesh.triangles;
    const auto& P = mesh.positions;
    auto remove_from = [&](std::uint32_t* list, std::uint32_t& count, std::uint32_t x) {
      for (std::uint32_t k = 0; k < count; ++k)
        if (list[k] == x) {
          list[k] = list[--count];
          list[count] = kNone;
          return;
        }
    };
    long long flips = 0;
    for (int pass = 0; pass < 4; ++pass) {
      long long pass_flips = 0;
      for (std::uint32_t u = 0; u < nv(); ++u) {
        for (std::uint32_t k = 0; k < nbr_count[u]; ++k) {
          const std::uint32_t v = nb(u)[k];
          if (v < u) continue;
          // The two triangles on edge (u, v): t1 runs u→v, t2 runs v→u.
          std::uint32_t t1 = kNone, t2 = kNone, a = kNone, b = kNone;
          int found = 0;
          for (std::uint32_t q = 0; q < vtri_count[u]; ++q) {
            const std::uint32_t t = vt(u)[q];
            const auto& tri = T[t];
            for (int c = 0; c < 3; ++c) {
              const std::uint32_t x = tri[static_cast<size_t>(c)],
                                  y = tri[static_cast<size_t>((c + 1) % 3)],
                                  z = tri[static_cast<size_t>((c + 2) % 3)];
              if (x == u && y == v) t1 = t, a = z, ++found;
              if (x == v && y == u) t2 = t, b = z, ++found;
            }
          }
          if (found != 2 || t1 == kNone || t2 == kNone || a == b) continue;
          if (nbr_count[u] <= 3 || nbr_count[v] <= 3) continue;
          // A vertex of a singular curve has more triangles than neighbours: both lists count.
          const std::uint32_t full = static_cast<std::uint32_t>(cap) - 1;
          if (nbr_count[a] >= full || nbr_count[b] >= full || vtri_count[a] >= full ||
              vtri_count[b] >= full)
            continue;
          if (std::find(nb(a), nb(a) + nbr_count[a], b) != nb(a) + nbr_count[a]) continue;
          // Hysteresis: a flip must win clearly, or moving vertices would flip edges back and
          // forth. sin(α + β) ≥ 0 rejects most edges (α + β ≤ π) before any atan2.
          {
            const Vec3 a1 = P[u] - P[a], a2 = P[v] - P[a], b1 = P[v] - P[b], b2 = P[u] - P[b];
            const double sa = a1.cross(a2).norm(), ca = a1.dot(a2);
            const double sb = b1.cross(b2).norm(), cb = b1.dot(b2);
            if (sa * cb + ca * sb >= 0) continue;
          }
          if (detail::corner_angle(P[a], P[u], P[v]) + detail::corner_angle(P[b], P[v], P[u]) <=
              std::numbers::pi + kFlipMargin)
            continue;
          const Vec3 n1 = detail::area_normal(P[u], P[v], P[a]),
                     n2 = detail::area_normal(P[v], P[u], P[b]);
          const Vec3 m1 = detail::area_normal(P[u], P[b], P[a]),
                     m2 = detail::area_normal(P[b], P[v], P[a]);
          if (m1.norm() < min_area2 || m2.norm() < min_area2) continue;
          if (n1.dot(n2) < cos_max * n1.norm() * n2.norm()) continue;
          if (m1.dot(m2) < cos_max * m1.norm() * m2.norm()) continue;
          const Vec3 old_sum = n1.normalized() + n2.normalized();
          if (!(m1.dot(old_sum) > 0) || !(m2.dot(old_sum) > 0)) continue;
          const Vec3 r1 = unit[u] + unit[b] + unit[a], r2 = unit[b] + unit[v] + unit[a];
          if ((n1.dot(unit[u] + unit[v] + unit[a]) > 0 && !(m1.dot(r1) > 0)) ||
              (n2.dot(unit[v] + unit[u] + unit[b]) > 0 && !(m2.dot(r2) > 0)))
            continue;
          const double q_old =
              std::min(detail::mean_ratio(P[u], P[v], P[a]), detail::mean_ratio(P[v], P[u], P[b]));
          const double q_new =
              std::min(detail::mean_ratio(P[u], P[b], P[a]), detail::mean_ratio(P[b], P[v], P[a]));
          if (!(q_new > q_old + kFlipMargin)) continue;
          T[t1] = {u, b, a};
          T[t2] = {b, v, a};
          remove_from(vt(u), vtri_count[u], t2);
          remove_from(vt(v), vtri_count[v], t1);
          vt(a)[vtri_count[a]++] = t2;
          vt(b)[vtri_count[b]++] = t1;
          remove_from(nb(u), nbr_count[u], v);
          remove_from(nb(v), nbr_count[v], u);
          nb(a)[nbr_count[a]++] = b;
          nb(b)[nbr_count[b]++] = a;
          ++pass_flips;
          --k;  // the slot now holds another neighbour
        }
      }
      flips += pass_flips;
      if (pass_flips == 0) break;
    }
    return flips;
  }

  void count_flipped() {
    long long flipped = 0;
    const long long nt = static_cast<long long>(mesh.triangles.size());
    detail::ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(static) reduction(+ : flipped)
    for (long long t = 0; t < nt; ++t)
      trap.run([&] {
        const auto& tri = mesh.triangles[static_cast<size_t>(t)];
        const Vec3 n = detail::area_normal(mesh.positions[tri[0]], mesh.positions[tri[1]],
                                           mesh.positions[tri[2]]);
        const Vec3 ref = unit[tri[0]] + unit[tri[1]] + unit[tri[2]];
        if (ref.squaredNorm() > 0 && n.dot(ref) < 0) ++flipped;
      });
    trap.rethrow();
    stats.flipped_triangles = flipped;
  }
};

MeshImprover::MeshImprover(Mesh mesh, const Surface& surface, const ImproveOptions& options) {
  detail::check_improve_options(options);
  surface.field.require_parameters();
  state_ = std::make_unique<State>(std::move(mesh), surface, options);
  State& s = *state_;
  s.init_modes();
  s.build_connectivity();
  s.mark_near_curves();
  s.update_mean_edge();
  s.stats.mean_edge_length = s.mean_edge;
  s.converged = s.mesh.triangles.empty();
}

MeshImprover::~MeshImprover() = default;
MeshImprover::MeshImprover(MeshImprover&&) noexcept = default;
MeshImprover& MeshImprover::operator=(MeshImprover&&) noexcept = default;

const ImproveStats& MeshImprover::step() {
  State& s = *state_;
  const auto t0 = Clock::now();
  if (s.mesh.triangles.empty()) {
    s.converged = true;
    return s.stats;
  }
  s.finished = false;
  s.evaluate_field();
  if ((s.opt.use_singularity || s.opt.find_singular_points) &&
      s.stats.steps % s.opt.singularity_interval == 0) {
    s.update_singularity_estimates();
    if (s.opt.find_singular_points) s.find_singular_points();
  }
  s.compute_moves();
  const double max_move = s.apply_moves();
  // Flips use the normals of this step's start: the vertices moved a fraction of an edge.
  if (s.opt.flip_edges && s.stats.steps < s.opt.flip_steps) s.stats.flips += s.flip_edges();
  s.update_mean_edge();
  ++s.stats.steps;
  s.stats.mean_edge_length = s.mean_edge;
  s.stats.max_move = s.mean_edge > 0 ? max_move / s.mean_edge : 0;
  s.converged = s.stats.max_move < s.opt.speed_threshold;
  s.stats.converged = s.converged;
  s.count_flipped();
  s.stats.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
  return s.stats;
}

bool MeshImprover::converged() const { return state_->converged; }

void MeshImprover::finish() {
  State& s = *state_;
  if (s.finished || s.mesh.triangles.empty()) return;
  const auto t0 = Clock::now();
  // A few guarded Newton projections onto F = 0 (onto the clip curve for boundary vertices).
  for (int round = 0; round < 4; ++round) {
    s.evaluate_field();
    const long long n = static_cast<long long>(s.nv());
    s.move.assign(s.nv(), Vec3::Zero());
    const double tiny = 1e-6 * s.grad_ref;
    detail::ExceptionTrap trap;
#pragma omp parallel for num_threads(s.workers) schedule(static)
    for (long long vv = 0; vv < n; ++vv)
      trap.run([&] {
        const std::uint32_t v = static_cast<std::uint32_t>(vv);
        if (s.mode[v] == kHeld || !std::isfinite(s.f[v])) return;
        double shortest = std::numeric_limits<double>::infinity();
        for (std::uint32_t k = 0; k < s.nbr_count[v]; ++k)
          shortest =
              std::min(shortest, (s.mesh.positions[s.nb(v)[k]] - s.mesh.positions[v]).norm());
        Vec3 d;
        if (s.mode[v] == kOnCurve) {
          d = project_onto_clip_curve(s.pool.local(), s.surface.clip, s.mesh.positions[v],
                                      0.5 * shortest) -
              s.mesh.positions[v];
        } else {
          const Vec3& g = s.grad[v];
          if (!(g.norm() > tiny)) return;
          d = surface_newton_step(s.f[v], g);
        }
        const double len = d.norm(), limit = 0.25 * shortest;
        if (len > limit) d *= limit / len;
        if (d.allFinite()) s.move[v] = d;
      });
    trap.rethrow();
    s.apply_moves();
  }
  s.evaluate_field();
  double worst = 0;
  long long undefined = 0;
  for (size_t v = 0; v < s.nv(); ++v) {
    const double g = s.grad[v].norm();
    // A vertex where F is not finite is not on F = 0, held or not: a failure, which
    // residual() makes the largest double. (Where only ∇F is infinite, as at the rim of
    // sqrt(x), F may well be 0: has_residual leaves it out below.)
    if (!std::isfinite(s.f[v])) {
      ++undefined;
      worst = residual(s.f[v], g);
      continue;
    }
    if (s.mode[v] == kHeld && !s.mesh.is_boundary[v]) continue;  // singular points, held border
    if (has_residual(s.f[v], g)) worst = std::max(worst, residual(s.f[v], g));
  }
  s.stats.undefined_vertices = undefined;
  s.stats.max_residual = worst;
  compute_field_normals(s.mesh, s.surface, s.opt.threads);
  s.count_flipped();
  s.finished = true;
  s.stats.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
}

const Mesh& MeshImprover::mesh() const { return state_->mesh; }
const ImproveStats& MeshImprover::stats() const { return state_->stats; }

Mesh MeshImprover::take_mesh() {
  Mesh m = std::move(state_->mesh);
  state_->mesh = Mesh{};
  return m;
}

}  // namespace zeroset
