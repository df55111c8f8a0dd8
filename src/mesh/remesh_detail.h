#pragma once
// The remesher's state (include/zeroset/mesh/remesh.h): a triangle list with per-vertex
// triangle lists, updated by the serial split/collapse/flip passes (remesh.cpp); relaxation and
// projection are parallel over the vertices (remesh_relax.cpp) and read a packed copy of the
// connectivity (CSR), rebuilt only when a topology pass changed it.
#include <algorithm>
#include <array>
#include <cstdint>
#include <stop_token>
#include <unordered_set>
#include <utility>
#include <vector>

#include "mesh_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/mesh/remesh.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset::detail {

using Tri = std::array<std::uint32_t, 3>;

// kFree: moves on F = 0. kClip: slides along the clip curve. kLocked: never moves or goes away
// (singular points, singular curves, an open border that is not the clip, a fixed boundary).
enum Kind : std::uint8_t { kFree = 0, kClip = 1, kLocked = 2 };
// A valence target that does not count (curve vertices and nodes: their rings are not discs).
constexpr int kAnyValence = -1;
// The split/collapse band stays [4/5 L, 4/3 L] for this many iterations, then widens by
// kBandGrowth per iteration (see remesh()). Widening sooner and faster than 5 and 0.03 halves
// the iterations (the last ones made a few dozen collapses each, a topology pass costing
// about two relaxation steps) with the same angles and edge lengths (docs/meshing.md).
constexpr int kFixedBandIterations = 2;
constexpr double kBandGrowth = 0.1;
// Relaxation steps at most once the connectivity is at rest.
constexpr int kMaxSettleSteps = 200;
// Delaunay flip rounds without relaxation after the polish rounds, at most.
constexpr int kFlipOnlyRounds = 20;
// Batched Newton steps onto F = 0 per relaxation step (then one at a time where needed).
constexpr int kBatchNewtonSteps = 3;
// Relaxation's Newton steps work through the vertices in chunks of this many.
constexpr long long kNewtonChunk = 2048;
// A relaxation step's first Newton step shorter than this (in L) ends its Newton's method
// without F and ∇F evaluated where it lands (Remesher::relax): most moves are so short that
// this saves one of the two evaluations per vertex and step. final_projection() then puts
// every vertex onto F = 0 to the rounding floor.
constexpr double kShortNewtonStep = 1e-3;
// While settling, a vertex that moves by rest_move L or more repeats its step (tangent-plane
// move towards the same centroid, then back onto F = 0) up to this many more times (see
// Remesher::relax).
constexpr int kSettleRepeats = 3;

// From this many vertices on, and with RemeshOptions::threads = 0, relaxation runs on all
// cores or on one, whichever its steps measure faster (MeasuredWorkers); a smaller mesh on one.
constexpr size_t kMeasuredWorkersVertices = 20000;

// From this many vertices on the remesher numbers the mesh again after its first topology
// passes, for locality (Remesher::renumber); a smaller mesh fits in the cache.
constexpr size_t kRenumberVertices = 16384;

// Next to pinch points the spring–mass improver relaxes the mesh within this many L of each,
// the rim held, and the remesher then holds every vertex within kPinchHoldRadius L
// (remesh_pinch.cpp).
constexpr double kPinchSpringRadius = 9;
constexpr double kPinchHoldRadius = 6;

inline double min_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  return std::min({corner_angle(a, b, c), corner_angle(b, c, a), corner_angle(c, a, b)});
}

struct PinchStep {
  bool improved = false;  // false: no pinch point, or the step was undone
  bool converged = false;
  int steps = 0;
  std::vector<std::uint32_t> held;  // the vertices the remesher holds
};
// The mesh within kPinchSpringRadius L of the pinch points improved by the spring–mass
// improver (improve_mesh), the triangles with a corner outside held.
PinchStep improve_near_pinch_points(Mesh& mesh, const Surface& surface,
                                    const std::vector<Vec3>& pinches, double L,
                                    const RemeshOptions& opt, std::stop_token stop);

struct Remesher {
  Mesh& mesh;
  const Surface& surface;
  RemeshOptions opt;
  // Relaxation's workers: as asked, or (RemeshOptions::threads = 0) one or all cores as
  // measured step by step (relax()). Every loop's result is the same for any number.
  int workers = 1;
  bool measure_workers = false;
  MeasuredWorkers worker_choice{1};
  EvaluatorPool pool;
  RemeshStats stats;

  std::vector<std::uint8_t> kind, alive_vertex, alive_tri;
  std::vector<std::vector<std::uint32_t>> vt;  // live triangles of each vertex
  std::unordered_set<std::uint64_t> curve_edges;
  std::vector<std::uint8_t> on_curve;  // vertex of a singular curve or node (always kLocked)
  // A free vertex next to a pinch point, where the spring–mass improver has placed it
  // (remesh_pinch.cpp): it neither relaxes nor goes away, and is projected onto F = 0 at the end.
  std::vector<std::uint8_t> pinch_held;
  double L = 0, lo = 0, hi = 0, min_area = 0;
  double hi_collapse = 0;
  std::vector<Vec3> pending;  // singular points no vertex holds yet
  std::vector<int> valence;   // during valence_flips: neighbours per vertex, kept up to date

  // Relaxation's view of the connectivity, rebuilt when a topology pass has changed it: the
  // live triangles packed, and each vertex's among them in CSR form (ring_tri[ring_start[v] ..
  // ring_start[v + 1]]). Contiguous, unlike vt, and without the dead triangles.
  bool rings_stale = true;
  std::vector<Tri> rtri;
  std::vector<std::uint32_t> ring_start, ring_tri;
  // The chains of clip vertices along the border (see border_targets), each with its two
  // ends (its first vertex again on a loop), in CSR form; rebuilt with the rings.
  std::vector<std::uint32_t> chain_start, chain_vertex;
  // The vertices relaxation moves, rebuilt with the rings: the free ones (not held next to a
  // pinch point) and the clip ones, each with a live triangle.
  std::vector<std::uint32_t> free_vs, clip_vs;
  // Area normal, twice the area, and that times the sum of the corners (three times the
  // centroid: the division by three is made once per vertex, not per triangle) of each packed
  // triangle at the current positions (triangle_normals), shared by its corners' centroids
  // and by apply_guarded's "before".
  std::vector<Vec3> rnormal, rmoment;
  std::vector<double> rarea;
  // ∇F where it was last evaluated (grad_at; NaN: never): a vertex that did not move since
  // needs no new evaluation for its tangent plane.
  std::vector<Vec3> grad_at, grad;

  Remesher(Mesh& m, const Surface& s, const RemeshOptions& o)
      : mesh(m),
        surface(s),
        opt(o),
        workers(o.threads > 0                                    ? worker_count(o.threads)
                : m.positions.size() >= kMeasuredWorkersVertices ? worker_count(0)
                                                                 : 1),
        measure_workers(o.threads == 0 && workers > 1),
        worker_choice(workers),
        pool(s.field, workers) {}

  Evaluator& ev() { return pool.at(0); }

  Vec3 normal(const Tri& t) const {
    const auto& p = mesh.positions;
    return area_normal(p[t[0]], p[t[1]], p[t[2]]);
  }

  // Whether a triangle with (area) normal n over the corners of t faces along ∇F at each
  // corner whose gradient is known (cached at or near the corner; zero when not yet evaluated)
  // and that is not locked (the singular set's vertices are). An operation may not turn a
  // triangle that agreed into one that does not: on a tube a few edges around, moves that each
  // tilt a triangle by less than the guards allow would otherwise flatten it into a band
  // (docs/meshing.md). The dot product first: it nearly always settles it.
  bool agrees_with_gradient(const Vec3& n, const Tri& t) const {
    for (std::uint32_t v : t)
      if (!(n.dot(grad[v]) > 0) && kind[v] != kLocked && grad[v] != Vec3::Zero()) return false;
    return true;
  }

  // The live triangles on edge (a, b).
  int edge_tris(std::uint32_t a, std::uint32_t b, std::uint32_t out[2]) const {
    int n = 0;
    for (std::uint32_t t : vt[a]) {
      const Tri& tr = mesh.triangles[t];
      if (tr[0] == b || tr[1] == b || tr[2] == b) {
        if (n < 2) out[n] = t;
        ++n;
      }
    }
    return n;
  }

  void neighbours(std::uint32_t v, std::vector<std::uint32_t>& out) const {
    out.clear();
    for (std::uint32_t t : vt[v])
      for (std::uint32_t w : mesh.triangles[t])
        if (w != v) out.push_back(w);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }

  // 6 inside, 4 on a border (the clip curve or a held open border), none on a singular curve
  // or point (their rings are not discs).
  int valence_target(std::uint32_t v) const {
    if (on_curve[v]) return kAnyValence;
    return kind[v] == kFree ? 6 : 4;
  }

  // ---- set-up and topology passes (remesh.cpp)
  void setup();
  // The isolated singular points to hold (into `pending`), from the surface's own list and
  // the singular set found.
  void find_singular_points(const SingularSet& set);
  // The nearest vertex that can goes exactly onto each pending point and stays there; points
  // no vertex could take stay pending.
  void hold_pending_points();
  std::vector<std::array<std::uint32_t, 2>> edges_where(bool longer) const;
  std::uint32_t add_vertex(const Vec3& p, Kind k);
  std::uint32_t add_triangle(const Tri& t);
  void drop_from(std::uint32_t v, std::uint32_t t);
  // rtri, ring_start and ring_tri from the live triangles, and the border chains.
  void build_rings();
  void build_border_chains();
  // rnormal, rarea and rmoment at the current positions.
  void triangle_normals();
  // Drops the dead vertices and triangles and numbers the rest along a space-filling curve,
  // so that neighbours lie near each other in memory (the splits append theirs at the end).
  void renumber();
  long long split_pass();
  // Collapses v into w (w stays where it is). Returns false, changing nothing, when refused.
  bool try_collapse(std::uint32_t v, std::uint32_t w, std::vector<std::uint32_t>& nv,
                    std::vector<std::uint32_t>& nw);
  long long collapse_pass();
  // Flips edge (a, b) of triangles t1 = (a, b, c), t2 = (b, a, d) into (a, d, c), (d, b, c)
  // when `wanted` says so and the geometry allows it; `may_want(a, b, c)` rules edges out
  // before the other triangle is looked up.
  template <class MayWant, class Wanted>
  long long flip_pass(MayWant may_want, Wanted wanted);
  long long valence_flips();
  long long delaunay_flips();

  // ---- relaxation, projection and output (remesh_relax.cpp)
  // Newton onto F = 0 (onto the clip curve F = 0 ∩ G = 0 for kClip vertices) from `from`.
  // False when it does not get there within `reach`, or meets a point where F or ∇F is not
  // finite or ∇F vanishes.
  bool project(bool on_clip, Vec3& p, double reach);
  // The two border neighbours of a clip vertex (kNone where it has not exactly two).
  std::array<std::uint32_t, 2> border_neighbours(std::uint32_t v) const;
  // Targets for the clip vertices: each chain of them along the border (between two vertices
  // that do not slide, or a closed loop from its first vertex) evenly spaced by arc length on
  // its polyline. Relaxing by neighbour midpoints instead converges as slowly as a 1-D Jacobi
  // iteration (about 1% per step on a chain of 20); this lands in one step up to the
  // polyline's error.
  void border_targets(std::vector<Vec3>& target, std::vector<std::uint8_t>& has);
  // One Jacobi step: every free vertex to the area-weighted centroid of its ring, in the
  // tangent plane, and every clip vertex to its border target along the clip curve; then back
  // onto F = 0 (the curve). Moves that would turn a triangle over or flatten it are undone.
  // Returns the largest move over L. relax() picks the workers and times the step
  // (measure_workers); relax_step() is the step.
  double relax();
  double relax_step();
  // Extra repeats of a vertex's step where it moves by rest_move L or more (0, or
  // kSettleRepeats while settling).
  int step_repeats = 0;
  // ∇F at the current position of every listed vertex, from the cache where it is there.
  void update_gradients(const std::vector<std::uint32_t>& vs);
  // Moves every vertex to `next` except where a triangle would turn over or flatten: there
  // the triangle's vertices stay (repeated until no triangle is bad).
  double apply_guarded(std::vector<Vec3>& next);
  // Newton projection of every moving vertex onto F = 0 (the clip curve for kClip), guarded.
  void final_projection();
  void compact();
  void measure_residual();
};

}  // namespace zeroset::detail
