// Storage of the floaters' state (growth, removal, reordering) and the field at every floater.
#include "floater_state_detail.h"

namespace zeroset::detail {

void push_floater(FloaterState& sys, const Vec3& p, double s, double m) {
  sys.pos.push_back(p);
  sys.sigma.push_back(s);
  sys.id.push_back(sys.next_id++);
  sys.mu.push_back(m);
  sys.smax.push_back(m * sigma_max(sys));
  sys.age.push_back(0);
  sys.pinned.push_back(kFree);
  sys.rail.push_back(-1);
  sys.arc.push_back(0);
  sys.value.push_back(0);
  sys.gnorm.push_back(0);
  sys.unit.push_back(Vec3::Zero());
}

void move_floater(FloaterState& sys, std::size_t from, std::size_t to) {
  sys.pos[to] = sys.pos[from];
  sys.sigma[to] = sys.sigma[from];
  sys.id[to] = sys.id[from];
  sys.mu[to] = sys.mu[from];
  sys.smax[to] = sys.smax[from];
  sys.age[to] = sys.age[from];
  sys.pinned[to] = sys.pinned[from];
  sys.rail[to] = sys.rail[from];
  sys.arc[to] = sys.arc[from];
  sys.value[to] = sys.value[from];
  sys.gnorm[to] = sys.gnorm[from];
  sys.unit[to] = sys.unit[from];
}

namespace {

constexpr std::size_t kStateArrays = 12;

// Every per-floater array, in one order: what moves, is resized and is permuted together.
auto state_arrays(FloaterState& sys) {
  return std::tie(sys.pos, sys.sigma, sys.id, sys.mu, sys.smax, sys.age, sys.pinned, sys.rail,
                  sys.arc, sys.value, sys.gnorm, sys.unit);
}

// out[s] = v[order[s]]: a worksharing loop inside the caller's parallel region (nowait: each
// array has its own output).
template <class T>
void permute_into(const std::vector<T>& v, std::vector<T>& out,
                  std::span<const std::uint32_t> order) {
  // No ExceptionTrap: copies of numbers and fixed-size vectors into arrays already sized
  // cannot throw.
#pragma omp for schedule(static) nowait
  for (std::int64_t s = 0; s < static_cast<std::int64_t>(order.size()); ++s)
    out[static_cast<std::size_t>(s)] = v[order[static_cast<std::size_t>(s)]];
}

}  // namespace

void resize_state(FloaterState& sys, std::size_t n) {
  std::apply([n](auto&... v) { (fit(v, n), ...); }, state_arrays(sys));
}

// Reorders every floater's state by `order` (new index → old index), in one parallel region.
// The reordered arrays are then the state's, and the state's old arrays are kept for the next
// time.
void permute_state(FloaterState& sys, std::span<const std::uint32_t> order) {
  auto now = state_arrays(sys);
  static_assert(std::tuple_size_v<decltype(now)> == kStateArrays);
  std::apply([&](auto&... v) { (fit(v, order.size()), ...); }, sys.permuted);
#pragma omp parallel num_threads(sys.threads) if (order.size() >= kParallelMin)
  [&]<std::size_t... k>(std::index_sequence<k...>) {
    (permute_into(std::get<k>(now), std::get<k>(sys.permuted), order), ...);
  }
  (std::make_index_sequence<kStateArrays>{});
  [&]<std::size_t... k>(std::index_sequence<k...>) {
    (std::get<k>(now).swap(std::get<k>(sys.permuted)), ...);
  }
  (std::make_index_sequence<kStateArrays>{});
}

// F and ∇F at every floater, batched in fixed chunks; and, for residual_stats(), the residual
// |F|/|∇F| of each floater not held on a node, counted by binary exponent per thread, and the
// largest residual per thread; and the extent of the floaters for build_neighbours().
void evaluate_all(FloaterState& sys) {
  const std::size_t n = floater_count(sys);
  const auto team = static_cast<std::size_t>(sys.threads);
  fit(sys.residuals, n);
  sys.octave_counts.resize(team);
  for (auto& counts : sys.octave_counts) counts.fill(0);
  sys.thread_largest.assign(team, 0.0);
  sys.thread_sigma.assign(team, 0.0);
  sys.thread_bounds.assign(team, empty_bounds());
  parallel_chunks(sys, n, [&](std::size_t b, std::size_t e, Evaluator& ev) {
    // Kept in registers over the chunk, stored once: the threads' entries share cache lines.
    const auto t = static_cast<std::size_t>(worker_index());
    double largest = sys.thread_largest[t], sigma_bound = sys.thread_sigma[t];
    Box3 extent = sys.thread_bounds[t];
    std::array<double, kChunk> x, y, z, f, gx, gy, gz;
    const std::size_t m = e - b;
    for (std::size_t k = 0; k < m; ++k) {
      const Vec3& p = sys.pos[b + k];
      x[k] = p.x();
      y[k] = p.y();
      z[k] = p.z();
      widen(extent, p);
      sigma_bound = std::max(sigma_bound, sys.sigma[b + k]);
    }
    ev.values_gradients({x.data(), m}, {y.data(), m}, {z.data(), m}, {f.data(), m}, {gx.data(), m},
                        {gy.data(), m}, {gz.data(), m});
    auto& counts = sys.octave_counts[t];
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t i = b + k;
      const Vec3 g(gx[k], gy[k], gz[k]);
      const double len = g.norm();
      sys.value[i] = f[k];
      sys.gnorm[i] = len;
      sys.unit[i] = (len > 0 && std::isfinite(len)) ? Vec3(g / len) : Vec3(Vec3::Zero());
      if (sys.pinned[i]) {
        sys.residuals[i] = kNotListed;
        continue;
      }
      const double r = residual(f[k], len);
      sys.residuals[i] = r;
      ++counts[octave_of(r)];
      largest = std::max(largest, r);
    }
    sys.thread_largest[t] = largest;
    sys.thread_sigma[t] = sigma_bound;
    sys.thread_bounds[t] = extent;
  });
  // Maxima and minima do not depend on which thread saw which floater.
  sys.largest_sigma = *std::max_element(sys.thread_sigma.begin(), sys.thread_sigma.end());
  sys.bounds = empty_bounds();
  for (const Box3& part : sys.thread_bounds) {
    if (part.is_empty()) continue;  // a thread that had no chunk (or only NaN positions)
    widen(sys.bounds, part.lo);
    widen(sys.bounds, part.hi);
  }
  sys.shown_normals_valid = false;
}

}  // namespace zeroset::detail
