#include "zeroset/floaters/floaters.h"

#include <fmt/core.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <tuple>
#include <type_traits>
#include <utility>

#include "critical_detail.h"
#include "neighbour_filter_detail.h"
#include "pair_kernel_detail.h"
#include "rng_detail.h"
#include "spatial_hash_detail.h"
#include "zeroset/error.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/floaters/metrics.h"

namespace zeroset {
namespace {

using detail::Rng;
using detail::Stream;

// Floaters are processed in fixed chunks, whatever the thread count, so batched field
// evaluation sees the same batches (and gives the same bits) on 1 or 2 threads.
constexpr std::size_t kChunk = 256;
// Fewer floaters than this are stepped on one thread: a parallel region costs more than it
// saves, and much more when other processes keep the cores busy.
constexpr std::size_t kParallelMin = 4096;
// Storage is re-sorted by spatial cell this often, so neighbours stay close in memory.
constexpr std::size_t kResortInterval = 16;

// A box that widen() grows to the points given to it.
Box3 empty_bounds() {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  return {Vec3::Constant(kInf), Vec3::Constant(-kInf)};
}
// Widens b to hold p; a NaN coordinate does not count.
void widen(Box3& b, const Vec3& p) {
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
// Settled: the population changed by at most this fraction over the convergence window.
constexpr double kStationary = 0.01;
// σ never leaves [kMinRadius·σ̂, kMaxRadius·σ_max]; reaching the floor marks it degenerate.
constexpr double kMinRadius = 0.01;
constexpr double kMaxRadius = 2.0;
// One step moves a floater by at most this fraction of the scene radius, tangentially and
// normally, so a near-critical point of F (tiny ∇F, F ≠ 0) cannot fling it away.
constexpr double kMaxStepScene = 0.1;
// σ̂ chosen from the area assumes each floater covers about this many σ̂² at equilibrium
// (hexagonal spacing between 1.25σ̂ and 1.78σ̂).
constexpr double kAreaPerFloater = 2.0;
// A given σ̂ is kept at least this fraction of the scene radius (below, squares underflow).
constexpr double kMinNominal = 1e-9;
// Binary exponents of a nonnegative double (with its sign bit 0): the residual histogram's bins.
constexpr std::size_t kOctaves = 2048;
std::size_t octave_of(double r) { return std::bit_cast<std::uint64_t>(r) >> 52; }
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

// |F|/|∇F| without infinities: 0 on the surface, the largest double where ∇F = 0 and F ≠ 0.
double residual_of(double value, double gradient_norm) {
  if (value == 0) return 0;
  if (!std::isfinite(value) || !std::isfinite(gradient_norm))
    return std::numeric_limits<double>::max();
  const double r = std::abs(value) / gradient_norm;
  return std::isfinite(r) ? r : std::numeric_limits<double>::max();
}

// Two unit vectors spanning the plane orthogonal to the unit vector n (any basis if n = 0).
void tangent_basis(const Vec3& n, Vec3& t1, Vec3& t2) {
  if (n.squaredNorm() == 0) {
    t1 = Vec3::UnitX();
    t2 = Vec3::UnitY();
    return;
  }
  const Vec3 a = std::abs(n.x()) < 0.6 ? Vec3::UnitX() : Vec3::UnitY();
  t1 = n.cross(a).normalized();
  t2 = n.cross(t1);
}

void check(bool ok, const char* name, double value, const char* why) {
  if (!ok) throw InvalidArgument(name, fmt::format("{}", value), why);
}

void validate(const FloaterOptions& o) {
  auto finite = [](double v) { return std::isfinite(v); };
  check(finite(o.radius) && o.radius >= 0, "radius", o.radius,
        "must be a positive length (or 0 to choose it from the surface's area)");
  check(o.max_count >= 1 && o.max_count <= 100'000'000, "max_count",
        static_cast<double>(o.max_count), "must be between 1 and 100,000,000");
  check(o.seed_count <= 100'000'000, "seed_count", static_cast<double>(o.seed_count),
        "must be at most 100,000,000");
  check(finite(o.dt) && o.dt > 0, "dt", o.dt, "must be positive");
  check(finite(o.repulsion) && o.repulsion > 0, "repulsion", o.repulsion, "must be positive");
  check(finite(o.desired_energy_factor) && o.desired_energy_factor > 0, "desired_energy_factor",
        o.desired_energy_factor, "must be positive");
  check(finite(o.radius_rate) && o.radius_rate >= 0, "radius_rate", o.radius_rate,
        "must not be negative");
  check(finite(o.radius_damping) && o.radius_damping > 0, "radius_damping", o.radius_damping,
        "must be positive");
  check(finite(o.feedback) && o.feedback >= 0, "feedback", o.feedback, "must not be negative");
  check(finite(o.max_step_fraction) && o.max_step_fraction > 0, "max_step_fraction",
        o.max_step_fraction, "must be positive");
  check(finite(o.equilibrium_speed) && o.equilibrium_speed >= 0, "equilibrium_speed",
        o.equilibrium_speed, "must not be negative");
  check(finite(o.fission_energy_factor) && o.fission_energy_factor >= 0, "fission_energy_factor",
        o.fission_energy_factor, "must not be negative");
  check(finite(o.death_radius_factor) && o.death_radius_factor >= 0 && o.death_radius_factor < 1,
        "death_radius_factor", o.death_radius_factor, "must be in [0, 1)");
  check(finite(o.max_radius_factor) && o.max_radius_factor >= 1, "max_radius_factor",
        o.max_radius_factor, "must be at least 1");
  check(o.estimator_interval >= 1, "estimator_interval", o.estimator_interval,
        "must be at least 1");
  check(o.curvature_samples >= 1 && o.curvature_samples <= 64, "curvature_samples",
        o.curvature_samples, "must be between 1 and 64");
  check(finite(o.singular_scale) && o.singular_scale >= 0, "singular_scale", o.singular_scale,
        "must be a positive length (or 0 for scene_radius/3)");
  check(finite(o.min_radius_factor) && o.min_radius_factor > 0 && o.min_radius_factor <= 1,
        "min_radius_factor", o.min_radius_factor, "must be in (0, 1]");
  check(finite(o.radius_grading) && o.radius_grading >= 0, "radius_grading", o.radius_grading,
        "must not be negative");
  check(o.converge_window >= 1, "converge_window", o.converge_window, "must be at least 1");
  check(finite(o.converge_churn) && o.converge_churn >= 0, "converge_churn", o.converge_churn,
        "must not be negative");
  check(finite(o.converge_speed) && o.converge_speed >= 0, "converge_speed", o.converge_speed,
        "must not be negative");
  check(o.threads >= 0, "threads", o.threads, "must not be negative");
}

// What the gather pass reads of a floater, in hash slot order: one cache line each, as
// neighbours are visited in an order the slots only roughly follow.
struct alignas(64) Neighbour {
  double x, y, z;
  double sigma;
  double smax;        // σ_max^j
  double nx, ny, nz;  // unit normal, or 0 (pinned on a node, or ∇F = 0)
};
static_assert(sizeof(Neighbour) == detail::kRecordFields * sizeof(double));

}  // namespace

RadiusAdapt parse_radius_adapt(std::string_view text, std::string_view flag) {
  for (RadiusAdapt m : {RadiusAdapt::kWitkinHeckbert, RadiusAdapt::kCurvature,
                        RadiusAdapt::kSingular, RadiusAdapt::kMixed})
    if (text == to_string(m)) return m;
  throw InvalidArgument(std::string(flag), std::string(text),
                        "expected wh, curvature, singular or mixed");
}

std::string_view to_string(RadiusAdapt mode) {
  switch (mode) {
    case RadiusAdapt::kWitkinHeckbert:
      return "wh";
    case RadiusAdapt::kCurvature:
      return "curvature";
    case RadiusAdapt::kSingular:
      return "singular";
    case RadiusAdapt::kMixed:
      return "mixed";
  }
  return "mixed";
}

struct FloaterSystem::Impl {
  Surface surface;
  FloaterOptions opt;
  double sigma_hat = 1;       // σ̂ in use
  double singular_scale = 1;  // γ_s in use
  double scene_radius = 1;
  Box3 box;
  std::size_t step_count = 0;
  std::uint64_t next_id = 0;
  // The last converge_window steps, for StepStats::converged.
  struct Recent {
    std::size_t events = 0, count = 0;
    double speed = 0;
  };
  std::deque<Recent> recent;

  // Floater state, one entry per floater. value/gnorm/unit always belong to the current
  // positions and parameters.
  std::vector<Vec3> pos;
  std::vector<double> sigma;
  std::vector<std::uint64_t> id;
  std::vector<double> mu;    // μ_i from the estimators
  std::vector<double> smax;  // σ_max^i = μ_i σ_max, graded (see repulsion())
  std::vector<std::uint32_t> age;
  std::vector<std::uint8_t> pinned;  // sits on a node (snap_to_nodes) and does not move
  std::vector<double> value;
  std::vector<double> gnorm;
  std::vector<Vec3> unit;  // ∇F/|∇F|, or 0 where that is undefined

  // permute_state()'s output, one array per array of state(), kept from call to call.
  std::tuple<std::vector<Vec3>, std::vector<double>, std::vector<std::uint64_t>,
             std::vector<double>, std::vector<double>, std::vector<std::uint32_t>,
             std::vector<std::uint8_t>, std::vector<double>, std::vector<double>,
             std::vector<Vec3>>
      permuted;

  // Per-step scratch.
  std::vector<double> graded, fq, new_sigma;
  std::vector<Vec3> new_pos;
  std::vector<double> speed_sq;         // (|ṗ_i|/σ_i)²
  std::vector<std::uint8_t> near_flag;  // |ṗ_i| < γσ_i
  // Fates judged in move_one(), carried out in decide_fates().
  enum FateFlag : std::uint8_t { kStray = 1, kFission = 2, kDeath = 4 };
  std::vector<std::uint8_t> fate;
  std::vector<std::uint32_t> gone;
  std::vector<double> chunk_speed;  // per chunk of kChunk floaters: Σ (|ṗ_i|/σ_i)²
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
  const detail::FilterPath filter = detail::best_filter_path();
  detail::SpatialHash hash;

  std::vector<Evaluator> evaluators;
  // Per thread: the perimeter points of curvature_estimates() and their F and ∇F; and the
  // points of update_estimators() with F, ∇F and the Hessian's six entries.
  std::vector<std::array<std::vector<double>, 7>> perimeter;
  std::vector<std::array<std::vector<double>, 13>> hessian_batch;
  int threads = 1;
  mutable std::vector<Vec3> shown_normals;
  mutable bool shown_normals_valid = false;

  Impl(const Surface& s, const FloaterOptions& o) : opt(o) {
    validate(opt);
    adopt_surface(s);
    insert_random(initial_count());
    evaluate_all();
  }

  std::size_t initial_count() const {
    const std::size_t wanted = opt.seed_count > 0 ? opt.seed_count : 200;
    return std::min(wanted, opt.max_count);
  }

  void adopt_surface(const Surface& s) {
    s.field.require_parameters();
    box = s.bounds();  // throws BadInput for an unbounded clip
    surface = s;
    scene_radius = surface.scene_radius();
    resolve_lengths();
    evaluators.clear();
    ensure_evaluators();
  }

  void resolve_lengths() {
    if (opt.radius > 0) {
      // Beyond these bounds nothing sensible can happen (one floater larger than the scene, or
      // radii whose squares underflow), so σ̂ is kept inside them.
      sigma_hat = std::clamp(opt.radius, kMinNominal * scene_radius, scene_radius);
    } else {
      const double area = estimate_area(surface);
      const double target = std::max<double>(1, static_cast<double>(opt.max_count) / 3);
      sigma_hat = area > 0 ? std::sqrt(area / (kAreaPerFloater * target)) : scene_radius / 10;
      sigma_hat = std::clamp(sigma_hat, 1e-4 * scene_radius, scene_radius);
    }
    singular_scale = opt.singular_scale > 0 ? opt.singular_scale : scene_radius / 3;
  }

  void ensure_evaluators() {
    threads = detail::worker_count(opt.threads);
    while (static_cast<int>(evaluators.size()) < threads) evaluators.emplace_back(surface.field);
    perimeter.resize(evaluators.size());
    hessian_batch.resize(evaluators.size());
  }

  double sigma_max() const { return opt.max_radius_factor * sigma_hat; }
  double desired_energy() const { return opt.desired_energy_factor * opt.repulsion; }

  template <class Body>
  void parallel_chunks(std::size_t n, Body&& body) {
    const auto chunks = static_cast<std::int64_t>((n + kChunk - 1) / kChunk);
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) if (n >= kParallelMin)
    for (std::int64_t c = 0; c < chunks; ++c) {
      const std::size_t b = static_cast<std::size_t>(c) * kChunk;
      body(b, std::min(n, b + kChunk), evaluators[detail::worker_index()]);
    }
  }

  // ---- state bookkeeping ---------------------------------------------------------------------

  std::size_t size() const { return pos.size(); }

  void push(const Vec3& p, double s, double m) {
    pos.push_back(p);
    sigma.push_back(s);
    id.push_back(next_id++);
    mu.push_back(m);
    smax.push_back(m * sigma_max());
    age.push_back(0);
    pinned.push_back(0);
    value.push_back(0);
    gnorm.push_back(0);
    unit.push_back(Vec3::Zero());
  }

  void move_floater(std::size_t from, std::size_t to) {
    pos[to] = pos[from];
    sigma[to] = sigma[from];
    id[to] = id[from];
    mu[to] = mu[from];
    smax[to] = smax[from];
    age[to] = age[from];
    pinned[to] = pinned[from];
    value[to] = value[from];
    gnorm[to] = gnorm[from];
    unit[to] = unit[from];
  }

  auto state() { return std::tie(pos, sigma, id, mu, smax, age, pinned, value, gnorm, unit); }
  static constexpr std::size_t kStateArrays = 10;

  void resize_state(std::size_t n) {
    std::apply([n](auto&... v) { (fit(v, n), ...); }, state());
  }

  // out[s] = v[order[s]]: a worksharing loop inside the caller's parallel region (nowait: each
  // array has its own output).
  template <class T>
  static void permute_into(const std::vector<T>& v, std::vector<T>& out,
                           std::span<const std::uint32_t> order) {
#pragma omp for schedule(static) nowait
    for (std::int64_t s = 0; s < static_cast<std::int64_t>(order.size()); ++s)
      out[static_cast<std::size_t>(s)] = v[order[static_cast<std::size_t>(s)]];
  }

  // Reorders every floater's state by `order` (new index → old index), in one parallel region.
  // The reordered arrays are then the state's, and the state's old arrays are kept for the next
  // time.
  void permute_state(std::span<const std::uint32_t> order) {
    auto now = state();
    static_assert(std::tuple_size_v<decltype(now)> == kStateArrays);
    std::apply([&](auto&... v) { (fit(v, order.size()), ...); }, permuted);
#pragma omp parallel num_threads(threads) if (order.size() >= kParallelMin)
    [&]<std::size_t... k>(std::index_sequence<k...>) {
      (permute_into(std::get<k>(now), std::get<k>(permuted), order), ...);
    }(std::make_index_sequence<kStateArrays>{});
    [&]<std::size_t... k>(std::index_sequence<k...>) {
      (std::get<k>(now).swap(std::get<k>(permuted)), ...);
    }(std::make_index_sequence<kStateArrays>{});
  }

  // ---- seeding ------------------------------------------------------------------------------

  Vec3 random_point_in_clip(Rng& rng) const {
    Vec3 p = box.center();
    for (int attempt = 0; attempt < 64; ++attempt) {
      for (int k = 0; k < 3; ++k) p[k] = rng.uniform(box.lo[k], box.hi[k]);
      if (surface.clip.contains(p)) return p;
    }
    return surface.clip.project(p);  // a sliver of a clip volume: its boundary will do
  }

  std::size_t insert_random(std::size_t count) {
    count = std::min(count, opt.max_count - std::min(opt.max_count, size()));
    for (std::size_t k = 0; k < count; ++k) {
      Rng rng(opt.seed, next_id, 0, Stream::kInsert);
      push(random_point_in_clip(rng), sigma_hat, 1.0);
    }
    shown_normals_valid = false;
    return count;
  }

  // ---- field evaluation ---------------------------------------------------------------------

  // F and ∇F at every floater, batched in fixed chunks; and, for residual_stats(), the residual
  // |F|/|∇F| of each floater not held on a node, counted by binary exponent per thread, and the
  // largest residual per thread; and the extent of the floaters for build_neighbours().
  void evaluate_all() {
    const std::size_t n = size();
    const auto team = static_cast<std::size_t>(threads);
    fit(residuals, n);
    octave_counts.resize(team);
    for (auto& counts : octave_counts) counts.fill(0);
    thread_largest.assign(team, 0.0);
    thread_sigma.assign(team, 0.0);
    thread_bounds.assign(team, empty_bounds());
    parallel_chunks(n, [&](std::size_t b, std::size_t e, Evaluator& ev) {
      // Kept in registers over the chunk, stored once: the threads' entries share cache lines.
      const auto t = static_cast<std::size_t>(detail::worker_index());
      double largest = thread_largest[t], sigma_bound = thread_sigma[t];
      Box3 extent = thread_bounds[t];
      std::array<double, kChunk> x, y, z, f, gx, gy, gz;
      const std::size_t m = e - b;
      for (std::size_t k = 0; k < m; ++k) {
        const Vec3& p = pos[b + k];
        x[k] = p.x();
        y[k] = p.y();
        z[k] = p.z();
        widen(extent, p);
        sigma_bound = std::max(sigma_bound, sigma[b + k]);
      }
      ev.values_gradients({x.data(), m}, {y.data(), m}, {z.data(), m}, {f.data(), m},
                          {gx.data(), m}, {gy.data(), m}, {gz.data(), m});
      auto& counts = octave_counts[t];
      for (std::size_t k = 0; k < m; ++k) {
        const std::size_t i = b + k;
        const Vec3 g(gx[k], gy[k], gz[k]);
        const double len = g.norm();
        value[i] = f[k];
        gnorm[i] = len;
        unit[i] = (len > 0 && std::isfinite(len)) ? Vec3(g / len) : Vec3(Vec3::Zero());
        if (pinned[i]) {
          residuals[i] = kNotListed;
          continue;
        }
        const double r = residual_of(f[k], len);
        residuals[i] = r;
        ++counts[octave_of(r)];
        largest = std::max(largest, r);
      }
      thread_largest[t] = largest;
      thread_sigma[t] = sigma_bound;
      thread_bounds[t] = extent;
    });
    // Maxima and minima do not depend on which thread saw which floater.
    largest_sigma = *std::max_element(thread_sigma.begin(), thread_sigma.end());
    bounds = empty_bounds();
    for (const Box3& part : thread_bounds) {
      if (part.is_empty()) continue;  // a thread that had no chunk (or only NaN positions)
      widen(bounds, part.lo);
      widen(bounds, part.hi);
    }
    shown_normals_valid = false;
  }

  void apply_parameters(std::span<const double> q) {
    for (std::size_t k = 0; k < q.size(); ++k) {
      surface.field.set_parameter(static_cast<int>(k), q[k]);
      for (Evaluator& ev : evaluators) ev.set_parameter(static_cast<int>(k), q[k]);
    }
  }

  void check_parameters(std::span<const double> q) const {
    const std::size_t want = surface.field.parameter_names().size();
    if (q.size() != want)
      throw InvalidArgument(fmt::format("expected {} parameter values for {}, got {}", want,
                                        surface.label(), q.size()));
    for (std::size_t k = 0; k < q.size(); ++k)
      if (!std::isfinite(q[k]))
        throw InvalidArgument(surface.field.parameter_names()[k], fmt::format("{}", q[k]),
                              "a parameter must be finite");
  }

  // ---- Rösch et al. §3.3: μ_i from the curvature (α_i) and singularity (β_i) estimators ----

  // Every estimator_interval steps: μ_i for the fission radii, and floaters that have come
  // near a node are snapped onto it.
  void update_estimators() {
    const RadiusAdapt mode = opt.radius_adapt;
    const std::size_t n = size();
    const bool need_alpha = mode == RadiusAdapt::kCurvature || mode == RadiusAdapt::kMixed;
    const bool need_beta = mode == RadiusAdapt::kSingular || mode == RadiusAdapt::kMixed;
    const bool need_hessian = need_beta || opt.snap_to_nodes;
    if (!need_alpha && !need_hessian) return;
    std::vector<std::uint8_t> candidate(n, 0);
    const int samples = opt.curvature_samples;
    parallel_chunks(n, [&](std::size_t b, std::size_t e, Evaluator& ev) {
      const std::size_t m = e - b;
      std::vector<double> alpha(m, 1.0), beta(m, 1.0);
      if (need_hessian) {
        // F, ∇F and the Hessian at the chunk's floaters, in one batched evaluation.
        auto& v = hessian_batch[static_cast<std::size_t>(detail::worker_index())];
        for (auto& a : v) a.resize(m);
        for (std::size_t k = 0; k < m; ++k) {
          v[0][k] = pos[b + k].x();
          v[1][k] = pos[b + k].y();
          v[2][k] = pos[b + k].z();
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
          const auto regular = detail::regular_corrector(gradient, hessian);
          const bool may_snap = opt.snap_to_nodes && !pinned[i];
          if (regular && !(may_snap && regular->norm() < kSnapFraction * sigma[i])) {
            beta[k] = std::min(regular->norm() / singular_scale, 1.0);
            continue;
          }
          const detail::Corrector c = detail::newton_corrector(gradient, hessian);
          const double r = c.reaches ? c.step.norm() : std::numeric_limits<double>::infinity();
          beta[k] = std::isfinite(r) ? std::min(r / singular_scale, 1.0) : 1.0;
          candidate[i] =
              may_snap && r < kSnapFraction * sigma[i] && c.smallest > kNondegenerate * c.largest;
        }
      }
      if (need_alpha) curvature_estimates(b, e, samples, ev, alpha);
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
        mu[b + k] = 0.5 * (mu[b + k] + std::clamp(f, opt.min_radius_factor, 1.0));
      }
    });
    if (opt.snap_to_nodes) snap(candidate);
  }

  // Newton's method on ∇F = 0 from p, staying within `reach` of it. Succeeds at a
  // nondegenerate critical point that lies on the surface (F there is negligible against the
  // change of F over the floater's radius): a node.
  std::optional<Vec3> find_node(Evaluator& ev, const Vec3& p, double reach) const {
    Vec3 q = p;
    for (int it = 0; it < kNodeIterations; ++it) {
      const FieldSample fs = ev.sample(q, true, false);
      const detail::Corrector c = detail::newton_corrector(fs.gradient, fs.hessian);
      if (!c.reaches || !(c.smallest > kNondegenerate * c.largest)) return std::nullopt;
      if (c.step.squaredNorm() == 0 || c.step.norm() <= 1e-14 * (q.norm() + scene_radius)) {
        const double change = c.largest * reach * reach;
        if (!(std::abs(fs.value) <= 1e-8 * change)) return std::nullopt;  // off the surface
        return q;
      }
      q -= c.step;
      if (!q.allFinite() || (q - p).norm() > reach) return std::nullopt;
    }
    return std::nullopt;
  }

  // Serial, so which floater takes a node does not depend on threads: the first candidate in
  // storage order whose Newton iteration lands on a node no floater holds yet.
  void snap(const std::vector<std::uint8_t>& candidate) {
    std::vector<Vec3> held;
    for (std::size_t i = 0; i < size(); ++i)
      if (pinned[i]) held.push_back(pos[i]);
    for (std::size_t i = 0; i < size(); ++i) {
      if (!candidate[i]) continue;
      const auto node = find_node(evaluators[0], pos[i], sigma[i]);
      if (!node || !surface.clip.contains(*node)) continue;
      const bool taken = std::any_of(held.begin(), held.end(), [&](const Vec3& h) {
        return (h - *node).norm() < 0.5 * sigma[i];
      });
      if (taken) continue;
      pos[i] = *node;
      pinned[i] = 1;
      held.push_back(*node);
      widen(bounds, *node);
    }
  }

  // After a parameter change nodes move: each pinned floater follows its node by Newton's
  // method, and is released when the node has gone (or turned degenerate).
  void track_nodes() {
    for (std::size_t i = 0; i < size(); ++i) {
      if (!pinned[i]) continue;
      const auto node = find_node(evaluators[0], pos[i], sigma[i]);
      if (node && surface.clip.contains(*node))
        pos[i] = *node;
      else
        pinned[i] = 0;
    }
  }

  // α_i = min_k |cos(∇F(p_i), ∇F(v_k))| over random points v_k on the floater's perimeter
  // (radius σ_i in the tangent plane), each moved onto F = 0 by one Newton step.
  void curvature_estimates(std::size_t b, std::size_t e, int samples, Evaluator& ev,
                           std::vector<double>& alpha) {
    const std::size_t m = (e - b) * static_cast<std::size_t>(samples);
    // Kept per thread from call to call: every entry used is written first.
    auto& [x, y, z, f, gx, gy, gz] = perimeter[static_cast<std::size_t>(detail::worker_index())];
    for (auto* v : {&x, &y, &z, &f, &gx, &gy, &gz}) v->resize(m);
    // Stratified angles θ_j = 2π(j + phase)/samples: every direction around the floater gets
    // looked at. Each is the previous one turned by 2π/samples (one sine and cosine per
    // floater instead of one per sample).
    const double turn = 2 * std::numbers::pi / samples;
    const double turn_cos = std::cos(turn), turn_sin = std::sin(turn);
    for (std::size_t k = 0; k < e - b; ++k) {
      const std::size_t i = b + k;
      Vec3 t1, t2;
      tangent_basis(unit[i], t1, t2);
      Rng rng(opt.seed, id[i], step_count, Stream::kCurvature);
      const double theta = turn * rng.uniform();
      double c = std::cos(theta), sn = std::sin(theta);
      for (int j = 0; j < samples; ++j) {
        const Vec3 v = pos[i] + sigma[i] * (c * t1 + sn * t2);
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
      Vec3 step = -(f[s] / g2) * g;
      const double limit = sigma[b + s / samples];
      if (step.norm() > limit) step *= limit / step.norm();
      x[s] += step.x();
      y[s] += step.y();
      z[s] += step.z();
    }
    ev.values_gradients(x, y, z, f, gx, gy, gz);
    for (std::size_t k = 0; k < e - b; ++k) {
      const Vec3& n = unit[b + k];
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

  // ---- the step -----------------------------------------------------------------------------

  // Builds the hash over the current positions and sizes the neighbour data in slot order (it is
  // filled by pack_slot() in repulsion_and_move()'s parallel region).
  void build_neighbours() {
    const std::size_t n = size();
    // The largest σ and the floaters' bounding box, as evaluate_all() found them.
    const double largest = largest_sigma;
    // The grid covers the floaters' bounding box within the clip's: a surface that lies flat
    // in its box gets few cells across it.
    Box3 region = box;
    for (int k = 0; k < 3; ++k) {
      region.lo[k] = std::max(region.lo[k], bounds.lo[k]);
      region.hi[k] = std::min(region.hi[k], bounds.hi[k]);
    }
    if (region.is_empty()) region = box;
    // Cells as large as the largest reach 3σ: a floater's neighbours lie in the 3×3×3 cells
    // around its own. (Smaller cells hold fewer candidates; measured on the Kummer scene, the
    // extra ranges and the larger grid cost as much as they save.)
    hash.build(pos, region, 3 * largest, threads);
    if (step_count % kResortInterval == 0) {
      permute_state(hash.order());
      hash.build(pos, region, 3 * largest, threads);
    }
    fit(packed, n);
    fit(pid, n);
    // The filter reads whole groups of slots past a range's end: padding keeps that in bounds.
    for (auto* v : {&fx, &fy, &fz, &fcut}) {
      fit(*v, n + detail::kFilterPad);
      std::fill(v->begin() + static_cast<std::ptrdiff_t>(n), v->end(), 0.0f);
    }
    // Single-precision coordinates for the prefilter: relative to the box centre, scaled into
    // [−1, 1] (see detail::prefilter_threshold). An infinite coordinate makes the scale 0, and
    // then every candidate passes to the exact test (a NaN one never passes either test).
    const Vec3 centre = box.center();
    double extent = 3 * largest;
    if (!bounds.is_empty())
      extent = std::max({extent, (bounds.lo - centre).cwiseAbs().maxCoeff(),
                         (bounds.hi - centre).cwiseAbs().maxCoeff()});
    prefilter_scale = extent > 0 && std::isfinite(extent) ? 1 / extent : 0;
  }

  // The neighbour data of the floater at slot s (build_neighbours() sized the arrays).
  void pack_slot(std::size_t s) {
    const std::uint32_t i = hash.order()[s];
    const Vec3 centre = box.center();
    const double scale = prefilter_scale;
    // A floater on a node has no tangent plane: it repels every sheet through the node.
    const Vec3 n = pinned[i] ? Vec3::Zero() : unit[i];
    packed[s] = {pos[i].x(), pos[i].y(), pos[i].z(), sigma[i], smax[i], n.x(), n.y(), n.z()};
    pid[s] = id[i];
    fx[s] = static_cast<float>((pos[i].x() - centre.x()) * scale);
    fy[s] = static_cast<float>((pos[i].y() - centre.y()) * scale);
    fz[s] = static_cast<float>((pos[i].z() - centre.z()) * scale);
    fcut[s] = detail::prefilter_threshold(3 * sigma[i] * scale);
  }

  // The constants of move_one() in this step.
  struct MoveConstants {
    double dt, e_hat, max_scene_step, lo, hi;
  };
  MoveConstants move_constants() const {
    return {opt.dt, desired_energy(), kMaxStepScene * scene_radius, kMinRadius * sigma_hat,
            kMaxRadius * sigma_max()};
  }

  // Pair terms are computed in batches of about this many pairs, over several floaters:
  // independent work for the processor, and the batch stays in the first-level cache.
  static constexpr std::size_t kPairBatch = 256;

  // Per-thread scratch of the pair pass: a cell's floaters, then those of its forward cells
  // (detail::SpatialHash::ForwardWalk) that may be within reach of one of them, their slots
  // and their single-precision coordinates and thresholds, contiguous; the indices into these
  // one floater's test kept; and the batch.
  struct Scratch {
    std::array<detail::SpatialHash::Range, detail::SpatialHash::kMaxForwardRanges> ranges;
    std::vector<std::uint32_t> slot;
    std::vector<float> x, y, z, cut;
    std::vector<std::uint32_t> near;
    detail::PairBatch batch;

    void reserve_candidates(std::size_t candidates) {
      const std::size_t size = candidates + detail::kFilterPad;
      if (slot.size() >= size) return;
      for (auto* v : {&slot, &near}) v->resize(size);
      for (auto* v : {&x, &y, &z, &cut}) v->resize(size);
    }
  };
  std::vector<Scratch> scratch;  // one per thread, kept from step to step
  std::vector<detail::PairSums> pair_sums;  // per slot

  // Pair pass (ALGORITHMS A.1–A.3, B): for floater i, E_i = Σ_j E_ij, ∂E_i/∂σ_i and the desired
  // velocity P_i = Σ_j r_ij (E_ij + (σ_i/σ_j)² E_ji) (or its scaled form). Each pair is computed
  // once, for both its floaters, by the cell of the one that comes first (in the cell's own slot
  // order, or by cell order): a cell pairs its floaters with its later floaters and with the
  // floaters of its 13 forward cells, which lie in its own layer of cells (SpatialHash::layers) and
  // the next. So layers of one parity can be worked on at once, each by one thread in slot order,
  // without two threads adding to the same sums: the even layers first, then the odd ones. Each
  // floater's sums take its pairs in a fixed order (those listed by even layers, then by odd ones;
  // in each, in listing order): the result does not depend on the number of threads.
  // The same pass grades the fission radii: σ_max^i ≤ σ_max^j + g·|r_ij| for every neighbour j (one
  // relaxation sweep per step). Without it, where μ_i jumps (α_i drops from ~1 to ~0 once a
  // floater's perimeter reaches across a node) the density wanted on either side differs by more
  // than fission and death tolerate (a factor 1/δ), and they fight forever. Then every floater
  // moves (move_one()), in the same parallel region.
  void repulsion_and_move() {
    const std::size_t n = size();
    for (auto* v : {&graded, &new_sigma, &speed_sq}) fit(*v, n);
    fit(new_pos, n);
    fit(fate, n);
    fit(near_flag, n);
    fit(pair_sums, n);
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    chunk_speed.resize(chunks);
    chunk_near.resize(chunks);
    scratch.resize(static_cast<std::size_t>(threads));
    const MoveConstants k = move_constants();
    const detail::PairConstants pk{opt.repulsion, opt.cos_weight ? 1.0 : 0.0,
                                   opt.radius_grading};
    const auto runs = hash.runs();
    const auto order = hash.order();
    const std::span<detail::PairSums> sums(pair_sums);
#pragma omp parallel num_threads(threads) if (n >= kParallelMin)
    {
      Scratch& c = scratch[static_cast<std::size_t>(detail::worker_index())];
      Evaluator& ev = evaluators[static_cast<std::size_t>(detail::worker_index())];
#pragma omp for schedule(static)
      for (std::int64_t slot = 0; slot < static_cast<std::int64_t>(n); ++slot) {
        const auto s = static_cast<std::size_t>(slot);
        pack_slot(s);
        sums[s] = {0, 0, 0, 0, 0, mu[order[s]] * sigma_max()};
      }
      const auto layers = hash.layers();
      const auto layer_runs = hash.layer_runs();
      detail::SpatialHash::ForwardWalk walk(hash);
      for (std::int64_t parity = 0; parity < 2; ++parity) {
#pragma omp for schedule(dynamic, 1)
        for (std::int64_t l = 0; l < static_cast<std::int64_t>(layers.size()); ++l) {
          const auto& layer = layers[static_cast<std::size_t>(l)];
          if ((layer.layer & 1) != parity) continue;
          for (std::uint32_t r = layer.first; r < layer.last; ++r) {
            const auto& run = runs[layer_runs[r]];
            const std::uint32_t candidates = gather_block(run, walk, c);
            for (std::uint32_t s = run.first; s < run.last; ++s) {
              // The later floaters of the cell and the forward cells' candidates.
              const detail::SpatialHash::Range later{s - run.first + 1, candidates};
              const std::size_t kept = detail::filter_near(
                  filter, {&later, 1}, c.x.data(), c.y.data(), c.z.data(), c.cut.data(), fx[s],
                  fy[s], fz[s], fcut[s], c.near.data());
              c.batch.add(s, c.slot.data(), c.near.data(), kept);
              if (c.batch.pairs() >= kPairBatch) accumulate(c.batch, pk);
            }
          }
          accumulate(c.batch, pk);  // the layer's pairs are all in the sums
        }
      }
#pragma omp for schedule(dynamic, 256)
      for (std::int64_t slot = 0; slot < static_cast<std::int64_t>(n); ++slot) {
        const auto s = static_cast<std::size_t>(slot);
        const std::uint32_t i = order[s];
        graded[i] = sums[s].limit;
        move_one(i, sums[s], ev, k);
      }
      // Summed per chunk in index order: the same on any number of threads.
#pragma omp for schedule(static)
      for (std::int64_t chunk = 0; chunk < static_cast<std::int64_t>(chunks); ++chunk) {
        const std::size_t b = static_cast<std::size_t>(chunk) * kChunk;
        double sq = 0;
        std::size_t near = 0;
        for (std::size_t i = b; i < std::min(n, b + kChunk); ++i) {
          sq += speed_sq[i];
          near += near_flag[i];
        }
        chunk_speed[static_cast<std::size_t>(chunk)] = sq;
        chunk_near[static_cast<std::size_t>(chunk)] = near;
      }
    }
    smax.swap(graded);
  }

  // The neighbour search tests single-precision distances first (detail::filter_box and
  // filter_near), keeping every pair within reach 3·max(σ_i, σ_j) and a few more (see
  // detail::prefilter_threshold); the pair terms (detail::pair_terms) then decide each
  // exactly. This is the first test, per cell: the cell's floaters, then those of its forward
  // cells within reach of the bounding box of the cell's floaters, copied into c (contiguous,
  // for the second test, per floater); returns how many.
  std::uint32_t gather_block(const detail::SpatialHash::Run& run,
                             detail::SpatialHash::ForwardWalk& walk, Scratch& c) const {
    const auto forward = std::span(c.ranges).first(
        static_cast<std::size_t>(walk.ranges(run.key, c.ranges)));
    const std::uint32_t own = run.last - run.first;
    std::size_t candidates = own;
    for (const auto& [first, last] : forward) candidates += last - first;
    c.reserve_candidates(candidates);
    const float *x = fx.data(), *y = fy.data(), *z = fz.data(), *cut = fcut.data();
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
        own + detail::filter_box(filter, forward, x, y, z, cut, lo, hi, reach, c.slot.data() + own);
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
  void accumulate(detail::PairBatch& batch, const detail::PairConstants& k) {
    batch.accumulate(opt.scaled_repulsion, k, reinterpret_cast<const double*>(packed.data()),
                     pid.data(), pair_sums);
  }

  // F_q·q̇ at every floater (exact parameter derivatives).
  void parameter_terms(std::span<const double> qdot) {
    const std::size_t n = size();
    fit(fq, n);
    std::fill(fq.begin(), fq.end(), 0.0);
    if (std::all_of(qdot.begin(), qdot.end(), [](double v) { return v == 0; })) return;
    parallel_chunks(n, [&](std::size_t b, std::size_t e, Evaluator& ev) {
      for (std::size_t i = b; i < e; ++i) {
        const FieldSample s = ev.sample(pos[i], false, true);
        double d = 0;
        for (std::size_t k = 0; k < qdot.size() && k < s.dq.size(); ++k) d += s.dq[k] * qdot[k];
        fq[i] = std::isfinite(d) ? d : 0;
      }
    });
  }

  // ALGORITHMS A.3–A.6 for floater i once its pair sums are complete (energy, σ_i³ ∂E_i/∂σ_i,
  // desired velocity and graded fission radius): radius adaptation, constrained velocity with the
  // φF and F_q·q̇ terms, bounded Euler step, clip projection; then its fate (judge()) and its
  // squared speed in radii per time unit and whether it is near equilibrium (for
  // StepStats::rms_speed and near_equilibrium). Reads and writes floater i's entries only.
  void move_one(std::size_t i, const detail::PairSums& sum, Evaluator& ev,
                const MoveConstants& k) {
    const double dt = k.dt, max_scene_step = k.max_scene_step;
    const double s = sigma[i];
    const double denergy = sum.de / (s * s * s);
    const double rate = -opt.radius_rate * (sum.e - k.e_hat) / (denergy + opt.radius_damping);
    new_sigma[i] = std::clamp(std::clamp(s + dt * rate, 0.5 * s, 2 * s), k.lo, k.hi);
    Vec3 p = pos[i];
    bool outside = false;
    if (!pinned[i]) {
      // Constrained velocity ṗ = P − [(F_x·P + F_q·q̇ + φF)/(F_x·F_x)] F_x, split into the
      // tangential part of P and the pull along the unit normal. Where ∇F vanishes (or F is
      // not finite) there is no normal: the floater moves by repulsion alone, and the pull
      // resumes as soon as it leaves the critical point.
      Vec3 tangential(sum.vx, sum.vy, sum.vz);  // the desired velocity
      Vec3 normal_move = Vec3::Zero();
      const Vec3& nrm = unit[i];
      if (nrm.squaredNorm() > 0 && std::isfinite(value[i])) {
        tangential -= nrm.dot(tangential) * nrm;
        double pull = -(opt.feedback * value[i] + fq[i]) / gnorm[i] * dt;
        if (!std::isfinite(pull)) pull = std::copysign(max_scene_step, pull);
        normal_move = std::clamp(pull, -max_scene_step, max_scene_step) * nrm;
      }
      Vec3 tangential_move = dt * tangential;
      const double limit = std::min(opt.max_step_fraction * s, max_scene_step);
      const double len = tangential_move.norm();
      if (len > limit) tangential_move *= limit / len;
      p += tangential_move + normal_move;
      if (opt.clip_projection) {
        const Vec3 projected = surface.clip.project(p);
        if (projected != p) p = onto_boundary_curve(ev, projected, s);
      } else {
        outside = !surface.clip.contains(p);
      }
    }
    const double speed = (p - pos[i]).norm() / dt;
    new_pos[i] = p;
    fate[i] = judge(i, sum.e, new_sigma[i], sum.limit, speed, outside);
    if (age[i] < std::numeric_limits<std::uint32_t>::max()) ++age[i];
    const double v = speed / new_sigma[i];
    speed_sq[i] = v * v;
    near_flag[i] = speed < opt.equilibrium_speed * new_sigma[i];
  }

  // What happens to floater i after its move (energy e, radius s, fission radius local_max,
  // speed |ṗ|), ALGORITHMS A.7: a stray is
  // removed; a floater near equilibrium may fission, or else die by the randomised density
  // rule. Whether a fission happens also depends on the population, so decide_fates() settles
  // that, serially. Pure: safe to call in parallel.
  std::uint8_t judge(std::size_t i, double e, double s, double local_max, double speed,
                     bool outside) const {
    const bool near_eq = speed < opt.equilibrium_speed * s;
    const double residual = residual_of(value[i], gnorm[i]);
    const bool stray =
        !std::isfinite(value[i]) ||
        (!pinned[i] && (s <= kMinRadius * sigma_hat || outside ||
                        (residual > sigma_hat && (near_eq || age[i] > kStrayAge))));
    if (stray) return kStray;
    if (!near_eq) return 0;
    const double local_nominal = std::min(sigma_hat, local_max);
    std::uint8_t f = 0;
    if (s > local_max ||
        (e > opt.fission_energy_factor * desired_energy() && s > local_nominal))
      f |= kFission;
    const double threshold = opt.death_radius_factor * local_nominal;
    if (s < threshold && !pinned[i]) {
      Rng rng(opt.seed, id[i], step_count, Stream::kDeath);
      if (rng.uniform() > s / threshold) f |= kDeath;
    }
    return f;
  }

  // Paper §3.2 projects a floater that left the clip back onto the clip's boundary, which
  // leaves it off F = 0 by about its step times the angle between surface and boundary; the
  // repulsion pushes it out again each step, so boundary floaters would never settle on the
  // surface. Newton's method along the boundary (in the direction of ∇F projected onto the
  // boundary's tangent plane) puts it on the curve F = 0 ∩ ∂clip instead.
  Vec3 onto_boundary_curve(Evaluator& ev, Vec3 p, double sigma_i) const {
    for (int it = 0; it < 2; ++it) {
      Vec3 g, ng;
      const double f = ev.value_gradient(p, g);
      surface.clip.value_gradient(p, ng);
      const Vec3 t = g - g.dot(ng) * ng;
      const double t2 = t.squaredNorm();
      if (!std::isfinite(f) || !(t2 > 0) || !std::isfinite(t2)) break;
      Vec3 step = -(f / t2) * t;
      const double len = step.norm();
      if (len > 0.5 * sigma_i) step *= 0.5 * sigma_i / len;
      p = surface.clip.project(p + step);
    }
    return p;
  }

  struct Fate {
    std::size_t births = 0, deaths = 0, removed = 0;
  };

  // ALGORITHMS A.7 with the fates judge() chose, serial so the outcome is the same on any
  // number of threads: at most one event per floater, and no fission beyond the cap.
  Fate decide_fates() {
    Fate result;
    const std::size_t n = size();
    std::size_t live = n;
    gone.clear();
    for (std::size_t i = 0; i < n; ++i) {
      if (fate[i] == 0) continue;
      if (fate[i] & kStray) {
        gone.push_back(static_cast<std::uint32_t>(i));
        --live;
        ++result.removed;
      } else if ((fate[i] & kFission) && live < opt.max_count && split(i)) {
        ++live;
        ++result.births;
      } else if (fate[i] & kDeath) {
        gone.push_back(static_cast<std::uint32_t>(i));
        --live;
        ++result.deaths;
      }
    }
    remove(gone);
    return result;
  }

  // Removes the floaters at the increasing indices `holes`, filling each with the last floater
  // that stays: O(removed) instead of moving everything behind the first hole.
  void remove(std::span<const std::uint32_t> holes) {
    std::size_t last = size(), front = 0, back = holes.size();
    while (front < back) {
      if (holes[back - 1] == last - 1) {  // the last floater goes too
        --back;
        --last;
        continue;
      }
      move_floater(last - 1, holes[front]);
      ++front;
      --last;
    }
    resize_state(last);
  }

  // Fission: both halves get σ/√2; the child starts at a random tangential offset of a quarter
  // to half the old radius (never zero: coincident twins would feel no force). Without clip
  // projection a child that would start outside the clip is not made (returns false).
  bool split(std::size_t i) {
    Rng rng(opt.seed, id[i], step_count, Stream::kFission);
    const double s = sigma[i];
    Vec3 t1, t2;
    tangent_basis(unit[i], t1, t2);
    const double theta = rng.uniform(0, 2 * std::numbers::pi);
    const double r = rng.uniform(0.25, 0.5) * s;
    Vec3 p = pos[i] + r * (std::cos(theta) * t1 + std::sin(theta) * t2);
    if (opt.clip_projection)
      p = surface.clip.project(p);
    else if (!surface.clip.contains(p))
      return false;
    sigma[i] = s / std::numbers::sqrt2;
    push(p, s / std::numbers::sqrt2, mu[i]);
    smax.back() = smax[i];
    return true;
  }

  StepStats step(std::span<const double> next_q) {
    const auto t0 = std::chrono::steady_clock::now();
    StepStats st;
    ensure_evaluators();
    if (size() == 0) {
      st.inserted = insert_random(initial_count());
      evaluate_all();
    }
    if (opt.radius_adapt == RadiusAdapt::kWitkinHeckbert) std::fill(mu.begin(), mu.end(), 1.0);
    if (step_count % static_cast<std::size_t>(opt.estimator_interval) == 0) update_estimators();

    std::vector<double> qdot;
    if (!next_q.empty()) {
      const auto q = surface.field.parameter_values();
      for (std::size_t k = 0; k < q.size(); ++k) qdot.push_back((next_q[k] - q[k]) / opt.dt);
    }
    build_neighbours();
    parameter_terms(qdot);
    repulsion_and_move();

    // Summed in chunk order: the same on any number of threads.
    double sq = 0;
    for (double v : chunk_speed) sq += v;
    st.rms_speed = size() > 0 ? std::sqrt(sq / static_cast<double>(size())) : 0;
    st.near_equilibrium = std::accumulate(chunk_near.begin(), chunk_near.end(), std::size_t{0});

    // Fates are judged on this step's motion and energies, at the moved positions.
    pos.swap(new_pos);
    sigma.swap(new_sigma);
    const Fate fates = decide_fates();
    if (!next_q.empty()) {
      apply_parameters(next_q);
      track_nodes();
    }
    evaluate_all();

    ++step_count;
    st.step = step_count;
    st.births = fates.births;
    st.deaths = fates.deaths;
    st.removed = fates.removed;
    st.count = size();
    st.converged = judge_convergence(st);
    residual_stats(st);
    st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return st;
  }

  bool judge_convergence(const StepStats& st) {
    const auto window = static_cast<std::size_t>(opt.converge_window);
    recent.push_back({st.births + st.deaths + st.removed + st.inserted, st.count, st.rms_speed});
    while (recent.size() > window + 1) recent.pop_front();
    if (recent.size() <= window || st.count == 0) return false;
    std::size_t events = 0;
    double speed = 0;
    for (std::size_t k = 1; k < recent.size(); ++k) {
      events += recent[k].events;
      speed += recent[k].speed;
    }
    const double n = static_cast<double>(st.count), w = static_cast<double>(window);
    const double drift = std::abs(n - static_cast<double>(recent.front().count));
    return static_cast<double>(events) <= opt.converge_churn * n * w && drift <= kStationary * n &&
           speed / w < opt.converge_speed;
  }

  // Median and largest |F|/|∇F| over the floaters not held on nodes (there F and ∇F both vanish
  // and the ratio means nothing), from what evaluate_all() counted. The median without sorting
  // them all: nonnegative doubles order like their bit patterns, so the histogram of binary
  // exponents finds the octave that holds the median, and only that octave is partially
  // sorted. Counts and maxima do not depend on which thread saw which floater.
  void residual_stats(StepStats& st) {
    std::array<std::size_t, kOctaves> counts{};
    double largest = 0;
    for (std::size_t t = 0; t < octave_counts.size(); ++t) {
      for (std::size_t o = 0; o < kOctaves; ++o) counts[o] += octave_counts[t][o];
      largest = std::max(largest, thread_largest[t]);
    }
    const std::size_t listed = std::accumulate(counts.begin(), counts.end(), std::size_t{0});
    if (listed == 0) return;
    std::size_t rank = listed / 2, o = 0;
    for (; rank >= counts[o]; ++o) rank -= counts[o];
    // The median octave counted again by the next kFineBits bits of the residuals, then the
    // median's fine bin collected and partly sorted (two passes over the residuals take less
    // time than collecting and sorting the whole octave).
    constexpr int kFineBits = 10;
    constexpr int kFineShift = 52 - kFineBits;
    std::array<std::uint32_t, std::size_t{1} << kFineBits> fine{};
    const auto bits = [&](std::size_t i) { return std::bit_cast<std::uint64_t>(residuals[i]); };
    for (std::size_t i = 0; i < size(); ++i)
      if ((bits(i) >> 52) == o) ++fine[(bits(i) >> kFineShift) & (fine.size() - 1)];
    std::size_t k = 0;
    for (; rank >= fine[k]; ++k) rank -= fine[k];
    const std::uint64_t bin = (std::uint64_t{o} << kFineBits) | k;
    median_octave.clear();
    for (std::size_t i = 0; i < size(); ++i)
      if ((bits(i) >> kFineShift) == bin) median_octave.push_back(residuals[i]);
    const auto mid = median_octave.begin() + static_cast<std::ptrdiff_t>(rank);
    std::nth_element(median_octave.begin(), mid, median_octave.end());
    st.median_residual = *mid;
    st.max_residual = largest;
  }

  // The floaters stay where they are, but nothing else of the old surface carries over: ages
  // (for stray detection), fission radii, nodes held, and the convergence history.
  void restart_on_new_surface() {
    for (std::size_t i = 0; i < size(); ++i) {
      pos[i] = surface.clip.project(pos[i]);
      sigma[i] = sigma_hat;
      age[i] = 0;
      pinned[i] = 0;
      mu[i] = 1;
      smax[i] = sigma_max();
    }
    recent.clear();
    evaluate_all();
  }

  void reset() {
    resize_state(0);
    next_id = 0;
    step_count = 0;
    recent.clear();
    insert_random(initial_count());
    evaluate_all();
  }

  void set_options(const FloaterOptions& o) {
    validate(o);
    const bool lengths = o.radius != opt.radius || o.singular_scale != opt.singular_scale ||
                         (o.radius == 0 && o.max_count != opt.max_count);
    opt = o;
    if (lengths) resolve_lengths();
    if (size() > opt.max_count) resize_state(opt.max_count);
    if (opt.radius_adapt == RadiusAdapt::kWitkinHeckbert) std::fill(mu.begin(), mu.end(), 1.0);
    ensure_evaluators();
    shown_normals_valid = false;
  }

  const std::vector<Vec3>& shown() const {
    if (!shown_normals_valid) {
      shown_normals.resize(size());
      for (std::size_t i = 0; i < size(); ++i)
        shown_normals[i] = unit[i].squaredNorm() > 0 ? unit[i] : Vec3(Vec3::UnitZ());
      shown_normals_valid = true;
    }
    return shown_normals;
  }
};

FloaterSystem::FloaterSystem(const Surface& surface, const FloaterOptions& options)
    : impl_(std::make_unique<Impl>(surface, options)) {}
FloaterSystem::~FloaterSystem() = default;
FloaterSystem::FloaterSystem(FloaterSystem&&) noexcept = default;
FloaterSystem& FloaterSystem::operator=(FloaterSystem&&) noexcept = default;

StepStats FloaterSystem::step() { return impl_->step({}); }

StepStats FloaterSystem::step(std::span<const double> next_parameters) {
  impl_->check_parameters(next_parameters);
  return impl_->step(next_parameters);
}

void FloaterSystem::set_parameters(std::span<const double> values) {
  impl_->check_parameters(values);
  impl_->apply_parameters(values);
  impl_->track_nodes();
  impl_->evaluate_all();
}

void FloaterSystem::set_parameter(std::string_view name, double value) {
  const int k = impl_->surface.field.parameter_index(name);
  if (k < 0)
    throw InvalidArgument(std::string(name), fmt::format("{}", value),
                          fmt::format("{} has no such parameter", impl_->surface.label()));
  std::vector<double> q = impl_->surface.field.parameter_values();
  q[static_cast<std::size_t>(k)] = value;
  set_parameters(q);
}

std::span<const double> FloaterSystem::parameters() const {
  return impl_->surface.field.parameter_values();
}

void FloaterSystem::set_surface(const Surface& surface) {
  impl_->adopt_surface(surface);
  impl_->restart_on_new_surface();
}

const Surface& FloaterSystem::surface() const { return impl_->surface; }

void FloaterSystem::set_options(const FloaterOptions& options) { impl_->set_options(options); }
const FloaterOptions& FloaterSystem::options() const { return impl_->opt; }

void FloaterSystem::reset() { impl_->reset(); }

void FloaterSystem::reseed(std::uint64_t seed) {
  impl_->opt.seed = seed;
  impl_->reset();
}

double FloaterSystem::nominal_radius() const { return impl_->sigma_hat; }
std::size_t FloaterSystem::size() const { return impl_->size(); }
std::size_t FloaterSystem::steps_taken() const { return impl_->step_count; }
std::span<const Vec3> FloaterSystem::positions() const { return impl_->pos; }
std::span<const double> FloaterSystem::radii() const { return impl_->sigma; }
std::span<const Vec3> FloaterSystem::normals() const { return impl_->shown(); }
std::span<const std::uint64_t> FloaterSystem::ids() const { return impl_->id; }
std::span<const double> FloaterSystem::max_radii() const { return impl_->smax; }

}  // namespace zeroset
