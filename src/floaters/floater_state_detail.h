#pragma once
// The state of a FloaterSystem, shared by the files of the floaters module: a plain struct
// with one array per floater property, and the free functions that work on it, declared here
// and defined by responsibility (state.cpp: storage and field evaluation; seeding.cpp: set-up
// and random insertion; estimators.cpp: α/β estimators and nodes; motion.cpp: neighbours and
// the move; population.cpp: fission and death; convergence.cpp: convergence and residuals).
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <deque>
#include <limits>
#include <optional>
#include <span>
#include <stop_token>
#include <tuple>
#include <vector>

#include "neighbour_filter_detail.h"
#include "pair_kernel_detail.h"
#include "rng_detail.h"
#include "spatial_hash_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/floaters/floaters.h"
#include "zeroset/surface/analysis.h"
#include "zeroset/surface/singular_index.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset::detail {

// Floaters are processed in fixed chunks, whatever the thread count, so batched field
// evaluation sees the same batches (and gives the same bits) on 1 or 2 threads.
constexpr std::size_t kChunk = 256;
// Fewer floaters than this are stepped on one thread: a parallel region costs more than it
// saves, and much more when other processes keep the cores busy.
constexpr std::size_t kParallelMin = 4096;
// Storage is re-sorted by spatial cell this often, so neighbours stay close in memory.
constexpr std::size_t kResortInterval = 16;
// A box that widen() grows to the points given to it.
inline Box3 empty_bounds() {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  return {Vec3::Constant(kInf), Vec3::Constant(-kInf)};
}
// Widens b to hold p; a NaN coordinate does not count.
inline void widen(Box3& b, const Vec3& p) {
  for (int k = 0; k < 3; ++k) {
    b.lo[k] = p[k] < b.lo[k] ? p[k] : b.lo[k];
    b.hi[k] = p[k] > b.hi[k] ? p[k] : b.hi[k];
  }
}
// A floater still far from F = 0 after this many steps is a stray (it never settles).
constexpr std::uint32_t kStrayAge = 200;
// Snapping to nodes: a floater whose Newton step towards ∇F = 0 is shorter than this fraction
// of its radius tries to reach the node; a node's Hessian has no eigenvalue below kNondegenerate
// times its largest (singular curves, with a null direction, are left to the dynamics).
constexpr double kSnapFraction = 0.5;
constexpr double kNondegenerate = 1e-3;
constexpr int kNodeIterations = 12;
// What holds a floater (FloaterState::pinned): nothing, a node it snapped onto (it follows the
// node while parameters move), a special point of the singular set, or a curve of it (it moves
// along the curve only). Held floaters have no normal: they repel every sheet through them.
enum Hold : std::uint8_t { kFree = 0, kOnNode = 1, kOnPoint = 2, kOnCurve = 3 };
// Settled: the population changed by at most this fraction over the convergence window.
constexpr double kStationary = 0.01;
// σ never leaves [kMinRadius·σ̂, kMaxRadius·σ_max]; reaching the floor marks it degenerate.
constexpr double kMinRadius = 0.01;
constexpr double kMaxRadius = 2.0;
// One step moves a floater by at most this fraction of the scene radius, tangentially and
// normally, so a near-critical point of F (tiny ∇F, F ≠ 0) cannot fling it away.
constexpr double kMaxStepScene = 0.1;
// A free floater whose |F|/|∇F| exceeds this fraction of its radius has its first-order pull
// checked against the zero along its normal (far_normal_root in motion.cpp): settled floaters
// lie far below it, so the check costs nothing once they are on the surface.
constexpr double kCheckedResidual = 1e-4;
// σ̂ chosen from the area assumes each floater covers about this many σ̂² at equilibrium
// (hexagonal spacing between 1.25σ̂ and 1.78σ̂).
constexpr double kAreaPerFloater = 2.0;
// A given σ̂ is kept at least this fraction of the scene radius (below, squares underflow).
constexpr double kMinNominal = 1e-9;
// Binary exponents of a nonnegative double (with its sign bit 0): the residual histogram's bins.
constexpr std::size_t kOctaves = 2048;
inline std::size_t octave_of(double r) { return std::bit_cast<std::uint64_t>(r) >> 52; }
// The residual of a floater held on a node, which is left out of the statistics: negative,
// so in no octave.
constexpr double kNotListed = -1;

// Resizes v to n, with room for an eighth more when it must grow: the floaters' number changes
// a little every step, and an array swapped with another from step to step (pos and new_pos,
// say) would otherwise be reallocated, every element moved, whenever the number grows.
template <class T>
void fit(std::vector<T>& v, std::size_t n) {
  if (v.capacity() < n) v.reserve(n + n / 8);
  v.resize(n);
}

// Two unit vectors spanning the plane orthogonal to the unit vector n (any basis if n = 0).
inline void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2) {
  if (n.squaredNorm() == 0) {
    t1 = Vec3::UnitX();
    t2 = Vec3::UnitY();
    return;
  }
  const Vec3 a = std::abs(n.x()) < 0.6 ? Vec3::UnitX() : Vec3::UnitY();
  t1 = n.cross(a).normalized();
  t2 = n.cross(t1);
}

// A curve of the singular set as floaters ride it: the polyline with the arc length at each
// vertex.
struct RailCurve {
  std::vector<Vec3> points;
  std::vector<double> arc;  // arc[0] = 0, arc.back() = length
  bool closed = false;
  CurveKind kind = CurveKind::kCrossing;
  std::vector<double> fixed;  // sorted arc lengths of the held points on it (its ends, ...)
  double length() const { return arc.back(); }
  // Arc length kept on the curve: wrapped when closed, clamped to [0, length] when open.
  double keep(double s) const {
    const double l = length();
    if (closed && l > 0) return s - l * std::floor(s / l);
    return std::clamp(s, 0.0, l);
  }
  // The segment holding arc length s (kept on the curve).
  std::size_t segment(double s) const {
    const auto it = std::upper_bound(arc.begin() + 1, arc.end() - 1, s);
    return static_cast<std::size_t>(it - arc.begin()) - 1;
  }
  Vec3 at(double s) const {
    const std::size_t k = segment(s);
    const double l = arc[k + 1] - arc[k];
    const double t = l > 0 ? std::clamp((s - arc[k]) / l, 0.0, 1.0) : 0.0;
    return points[k] + t * (points[k + 1] - points[k]);
  }
  Vec3 tangent(double s) const {
    const std::size_t k = segment(s);
    const Vec3 d = points[k + 1] - points[k];
    const double l = d.norm();
    return l > 0 ? Vec3(d / l) : Vec3(Vec3::Zero());
  }
};

// What the gather pass reads of a floater, in hash slot order: one cache line each, as
// neighbours are visited in an order the slots only roughly follow.
struct alignas(64) Neighbour {
  double x, y, z;
  double sigma;
  double smax;        // σ_max^j
  double nx, ny, nz;  // unit normal, or 0 (pinned on a node, or ∇F = 0)
};
static_assert(sizeof(Neighbour) == kRecordFields * sizeof(double));

// The last converge_window steps, for StepStats::converged.
struct RecentStep {
  std::size_t events = 0, count = 0;
  double speed = 0;
};

// Fates judged in move_one(), carried out in decide_fates().
enum FateFlag : std::uint8_t { kStray = 1, kFission = 2, kDeath = 4 };

// What decide_fates() did.
struct FateCounts {
  std::size_t births = 0, deaths = 0, removed = 0;
};

// The constants of move_one() in this step.
struct MoveConstants {
  double dt, e_hat, max_scene_step, lo, hi;
};

// Per-thread scratch of the pair pass: a cell's floaters, then those of its forward cells
// (SpatialHash::ForwardWalk) that may be within reach of one of them, their slots and their
// single-precision coordinates and thresholds, contiguous; the indices into these one
// floater's test kept; and the batch.
struct PairScratch {
  std::array<SpatialHash::Range, SpatialHash::kMaxForwardRanges> ranges;
  std::vector<std::uint32_t> slot;
  std::vector<float> x, y, z, cut;
  std::vector<std::uint32_t> near;
  PairBatch batch;

  void reserve_candidates(std::size_t candidates) {
    const std::size_t size = candidates + kFilterPad;
    if (slot.size() >= size) return;
    for (auto* v : {&slot, &near}) v->resize(size);
    for (auto* v : {&x, &y, &z, &cut}) v->resize(size);
  }
};

struct FloaterState {
  Surface surface;
  FloaterOptions opt;
  // Cuts the long set-up work short (area estimate, singular set search) once requested.
  std::stop_token stop;
  double sigma_hat = 1;       // σ̂ in use
  double singular_scale = 1;  // γ_s in use
  double scene_radius = 1;
  Box3 box;
  std::size_t step_count = 0;
  std::uint64_t next_id = 0;
  std::deque<RecentStep> recent;

  // Floater state, one entry per floater. value/gnorm/unit always belong to the current
  // positions and parameters.
  std::vector<Vec3> pos;
  std::vector<double> sigma;
  std::vector<std::uint64_t> id;
  std::vector<double> mu;    // μ_i from the estimators
  std::vector<double> smax;  // σ_max^i = μ_i σ_max, graded (see repulsion_and_move())
  std::vector<std::uint32_t> age;
  std::vector<std::uint8_t> pinned;  // a Hold: kOnNode and kOnPoint do not move
  std::vector<std::int32_t> rail;    // kOnCurve: the index of its curve in `rails`, else -1
  std::vector<double> arc;           // kOnCurve: its arc length along that curve
  std::vector<double> value;
  std::vector<double> gnorm;
  std::vector<Vec3> unit;  // ∇F/|∇F|, or 0 where that is undefined

  // permute_state()'s output, one array per array of state_arrays(), kept from call to call.
  std::tuple<std::vector<Vec3>, std::vector<double>, std::vector<std::uint64_t>,
             std::vector<double>, std::vector<double>, std::vector<std::uint32_t>,
             std::vector<std::uint8_t>, std::vector<std::int32_t>, std::vector<double>,
             std::vector<double>, std::vector<double>, std::vector<Vec3>>
      permuted;

  // The singular set (docs/algorithms.md B.7), found for the current surface and parameters
  // when `singular_current`; `singular_placed` once floaters are held on its points and curves.
  // While parameters move it is dropped, and found again once they have been still for
  // estimator_interval steps.
  SingularSet singular;
  SingularSetIndex singular_index;
  std::vector<RailCurve> rails;  // its curves with their arc lengths
  bool singular_current = false;
  bool singular_placed = false;
  std::size_t still_steps = 0;    // steps since the parameters last changed
  double rail_sigma = 0;          // σ of the floaters held on the set
  double rail_spacing = 0;        // their spacing along the curves
  std::vector<double> rail_push;  // per floater on a curve: its desired velocity along it

  // Per-step scratch.
  std::vector<double> graded, fq, new_sigma;
  std::vector<Vec3> new_pos;
  std::vector<double> speed_sq;         // (|ṗ_i|/σ_i)²
  std::vector<std::uint8_t> near_flag;  // |ṗ_i| < γσ_i
  std::vector<std::uint8_t> fate;       // FateFlag bits
  std::vector<std::uint32_t> gone;
  std::vector<double> chunk_speed;      // per chunk of kChunk floaters: Σ (|ṗ_i|/σ_i)²
  std::vector<std::size_t> chunk_near;  // and the count near equilibrium
  // residual_stats(): residuals (kNotListed for floaters on nodes), and their binary exponents
  // counted per thread (evaluate_all()), the largest per thread, and the residuals in the
  // median's bin.
  std::vector<double> residuals, thread_largest, median_octave;
  std::vector<std::array<std::size_t, kOctaves>> octave_counts;
  // The largest σ_i, and the floaters' bounding box (non-finite coordinates do not count), at
  // the last evaluate_all() (node snapping, which moves floaters after it, widens the latter);
  // per thread while they are found.
  double largest_sigma = 0;
  Box3 bounds;
  std::vector<double> thread_sigma;
  std::vector<Box3> thread_bounds;
  std::vector<Neighbour> packed;  // in slot order
  double prefilter_scale = 0;     // single-precision coordinates are scaled by it
  std::vector<std::uint64_t> pid;
  std::vector<float> fx, fy, fz, fcut;  // the prefilter's coordinates and thresholds
  const FilterPath filter = best_filter_path();
  SpatialHash hash;
  std::vector<PairScratch> scratch;  // one per thread, kept from step to step
  std::vector<PairSums> pair_sums;   // per slot

  std::vector<Evaluator> evaluators;
  // Per thread: the perimeter points of curvature_estimates() and their F and ∇F; and the
  // points of update_estimators() with F, ∇F and the Hessian's six entries.
  std::vector<std::array<std::vector<double>, 7>> perimeter;
  std::vector<std::array<std::vector<double>, 13>> hessian_batch;
  int threads = 1;
  mutable std::vector<Vec3> shown_normals;
  mutable bool shown_normals_valid = false;
};

inline std::size_t floater_count(const FloaterState& sys) { return sys.pos.size(); }
inline double sigma_max(const FloaterState& sys) {
  return sys.opt.max_radius_factor * sys.sigma_hat;
}
inline double desired_energy(const FloaterState& sys) {
  return sys.opt.desired_energy_factor * sys.opt.repulsion;
}
template <class Body>
void parallel_chunks(FloaterState& sys, std::size_t n, Body&& body) {
  const auto chunks = static_cast<std::int64_t>((n + kChunk - 1) / kChunk);
  ExceptionTrap trap;
#pragma omp parallel for schedule(dynamic, 1) num_threads(sys.threads) if (n >= kParallelMin)
  for (std::int64_t c = 0; c < chunks; ++c)
    trap.run([&] {
      const std::size_t b = static_cast<std::size_t>(c) * kChunk;
      body(b, std::min(n, b + kChunk), sys.evaluators[worker_index()]);
    });
  trap.rethrow();
}

// ---- storage and field evaluation (state.cpp) ----------------------------------------------

void push_floater(FloaterState& sys, const Vec3& p, double s, double m);
void move_floater(FloaterState& sys, std::size_t from, std::size_t to);
void resize_state(FloaterState& sys, std::size_t n);
// Reorders every floater's state by `order` (new index → old index).
void permute_state(FloaterState& sys, std::span<const std::uint32_t> order);
// F and ∇F at every floater, the residual statistics' counts and the floaters' extent.
void evaluate_all(FloaterState& sys);

// ---- set-up and seeding (seeding.cpp) ------------------------------------------------------

std::size_t initial_count(const FloaterState& sys);
void adopt_surface(FloaterState& sys, const Surface& s);
void resolve_lengths(FloaterState& sys);
void ensure_evaluators(FloaterState& sys);
std::size_t insert_random(FloaterState& sys, std::size_t count);
void apply_parameters(FloaterState& sys, std::span<const double> q);
void check_parameters(const FloaterState& sys, std::span<const double> q);

// ---- estimators and nodes (estimators.cpp) -------------------------------------------------

// μ_i from the α/β estimators, and snapping onto nodes.
void update_estimators(FloaterState& sys);
// Pinned floaters follow their nodes after a parameter change.
void track_nodes(FloaterState& sys);

// ---- the singular set (singular_floaters.cpp) ----------------------------------------------

// What the singular set's upkeep did to the population in one step.
struct SingularEvents {
  std::size_t inserted = 0, removed = 0;
};
// Finds the singular set of the current surface and parameters (when the options use it) and
// indexes it; floaters held on it are not placed yet.
void find_singular(FloaterState& sys);
// Every estimator_interval steps: finds the set again once the parameters have been still for
// that long, places floaters on its points and curves where none are, splits gaps along the
// curves wider than the sheets' spacing around them, and removes free floaters that have
// strayed onto an isolated curve (no sheet carries them there).
SingularEvents keep_singular_floaters(FloaterState& sys);
// The parameters or the surface change: floaters held on the old set's points and curves go,
// and the set is stale until found again. Returns how many floaters were removed.
std::size_t drop_singular_set(FloaterState& sys);
// The options change: the held floaters go (their spacing follows σ̂) and come back at the next
// upkeep; the index follows the new reach. Returns how many floaters were removed.
std::size_t replace_singular_floaters(FloaterState& sys);
// The desired velocity along its curve of every floater on one (rail_push): 1-D repulsion from
// its neighbours on the curve, the held points on it fixed.
void chain_velocities(FloaterState& sys);
// Distance from p to the singular set when within the index's reach, else infinity.
inline double singular_set_distance(const FloaterState& sys, const Vec3& p) {
  return sys.singular_current ? sys.singular_index.distance(p)
                              : std::numeric_limits<double>::infinity();
}

// ---- neighbours and motion (motion.cpp) ----------------------------------------------------

void build_neighbours(FloaterState& sys);
void parameter_terms(FloaterState& sys, std::span<const double> qdot);
void repulsion_and_move(FloaterState& sys);

// ---- fission and death (population.cpp) ----------------------------------------------------

// What happens to floater i after its move (energy e, radius s, fission radius local_max,
// speed |ṗ|), docs/algorithms.md A.7: a stray is
// removed; a floater near equilibrium may fission, or else die by the randomised density
// rule. Whether a fission happens also depends on the population, so decide_fates() settles
// that, serially. Pure: safe to call in parallel.
inline std::uint8_t judge_fate(const FloaterState& sys, std::size_t i, double e, double s,
                               double local_max, double speed, bool outside) {
  const bool near_eq = speed < sys.opt.equilibrium_speed * s;
  const double r = residual(sys.value[i], sys.gnorm[i]);
  const bool stray =
      !std::isfinite(sys.value[i]) ||
      (!sys.pinned[i] && (s <= kMinRadius * sys.sigma_hat || outside ||
                          (r > sys.sigma_hat && (near_eq || sys.age[i] > kStrayAge))));
  if (stray) return kStray;
  // Floaters held on the singular set's points and curves keep their radius and number.
  if (!near_eq || sys.pinned[i] >= kOnPoint) return 0;
  const double local_nominal =
      sys.opt.local_nominal_radius ? std::min(sys.sigma_hat, local_max) : sys.sigma_hat;
  std::uint8_t f = 0;
  if (s > local_max ||
      (e > sys.opt.fission_energy_factor * desired_energy(sys) && s > local_nominal))
    f |= kFission;
  const double threshold = sys.opt.death_radius_factor * local_nominal;
  if (s < threshold && !sys.pinned[i]) {
    Rng rng(sys.opt.seed, sys.id[i], sys.step_count, Stream::kDeath);
    if (rng.uniform() > s / threshold) f |= kDeath;
  }
  return f;
}
FateCounts decide_fates(FloaterState& sys);
// Removes the floaters at the increasing indices `holes`.
void remove_floaters(FloaterState& sys, std::span<const std::uint32_t> holes);
// Removes the floaters where F or ∇F is not finite, or that lie outside the clip (beyond
// rounding), after evaluate_all(); returns how many (then evaluate_all() has run again).
std::size_t remove_undefined(FloaterState& sys);

// ---- convergence (convergence.cpp) ---------------------------------------------------------

bool judge_convergence(FloaterState& sys, const StepStats& st);
void residual_stats(FloaterState& sys, StepStats& st);

}  // namespace zeroset::detail
