#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "rng_detail.h"
#include "spatial_hash_detail.h"
#include "zeroset/detail/parallel.h"

namespace zeroset::detail {
namespace {
// A dense grid may have this many rows of cells per point before hashing them is cheaper.
constexpr std::int64_t kDenseRowsPerPoint = 8;
constexpr std::int64_t kDenseMinRows = 1 << 14;
// Fewer points than this are sorted on one thread.
constexpr std::int64_t kSortParallelMin = 4096;
}  // namespace

std::size_t SpatialHash::lay_grid(const Box3& region, double cell, std::size_t points) {
  Vec3 extent;
  for (int k = 0; k < 3; ++k) {
    // A region that is not finite on an axis gets one cell across it there.
    const bool finite = std::isfinite(region.lo[k]) && std::isfinite(region.hi[k]);
    origin_[k] = finite ? std::min(region.lo[k], region.hi[k]) : 0.0;
    extent[k] = finite ? std::max(region.hi[k] - region.lo[k], 0.0) : 0.0;
  }
  const double max_extent = std::max(extent.maxCoeff(), 1e-300);
  const double min_cell = max_extent / static_cast<double>(std::int64_t{1} << (kBits - 1));
  if (!std::isfinite(cell) || cell <= 0) cell = max_extent;
  cell_ = std::max(cell, min_cell);
  inv_cell_ = 1 / cell_;
  std::array<std::int64_t, 3> across;
  for (int k = 0; k < 3; ++k)
    across[k] =
        std::max<std::int64_t>(1, static_cast<std::int64_t>(std::ceil(extent[k] * inv_cell_)));
  // The axis with the most cells (z on a tie) is the key's most significant: the one
  // ForwardWalk works across in layers.
  const int major =
      across[2] >= std::max(across[0], across[1]) ? 2 : (across[1] >= across[0] ? 1 : 0);
  axis_ = major == 2 ? std::array{0, 1, 2} : major == 1 ? std::array{0, 2, 1} : std::array{1, 2, 0};
  for (int k = 0; k < 3; ++k) {
    dims_[k] = across[static_cast<std::size_t>(axis_[k])];
    limit_[k] = static_cast<double>(dims_[k] - 1);
  }
  const std::int64_t rows = dims_[1] * dims_[2];  // each at most 2^21: no overflow
  const auto n = static_cast<std::int64_t>(points);
  dense_ = rows <= std::max(kDenseRowsPerPoint * n, kDenseMinRows);
  if (dense_) return static_cast<std::size_t>(rows);
  const std::size_t buckets =
      std::bit_ceil(static_cast<std::size_t>(std::max<std::int64_t>(2 * n, 16)));
  mask_ = buckets - 1;
  return buckets;
}

void SpatialHash::build(std::span<const Vec3> points, const Box3& region, double cell,
                        int threads) {
  const std::size_t n = points.size();
  const int team = n >= kSortParallelMin ? std::max(threads, 1) : 1;
  keys_.resize(n);
  order_.resize(n);
  key_in_.resize(n);
  const std::size_t buckets = lay_grid(region, cell, n);
  start_.resize(buckets + 1);
  bucket_run_.resize(buckets + 1);
  // A counting sort by bucket (a row of cells, or a hash of one), then each bucket sorted by
  // key. Each thread counts its contiguous part of the input per bucket; the prefix sums run
  // over (bucket, part), so each thread places its part at cursors of its own, in input order:
  // stable, and the same slots whatever the team. Floaters come kept in cell order, so the
  // counting and placing walk the buckets almost in order and the buckets come out almost
  // sorted. All in one parallel region (its threads wake once). Each phase between barriers
  // runs through the trap, so that every thread meets every barrier even after a failure.
  detail::ExceptionTrap trap;
#pragma omp parallel num_threads(team)
  {
    const auto part = static_cast<std::size_t>(detail::worker_index());
    const auto parts = static_cast<std::size_t>(detail::team_size());
#pragma omp single
    trap.run([&] {
      cursor_.assign(parts * buckets, 0);
      part_sums_.assign(parts + 1, 0);
      part_runs_.resize(parts);
    });
    // This thread's part of the input, and of the buckets.
    const std::size_t first = n * part / parts, last = n * (part + 1) / parts;
    const std::size_t bucket_first = buckets * part / parts;
    const std::size_t bucket_last = buckets * (part + 1) / parts;
    const CellOf cell_of(*this);
    trap.run([&] {
      std::uint32_t* cursor = cursor_.data() + part * buckets;
      with_density([&](auto dense) {
        for (std::size_t i = first; i < last; ++i) {
          const std::uint64_t key = cell_of.key(points[i]);
          key_in_[i] = key;
          ++cursor[bucket_index<dense()>(key)];
        }
      });
    });
#pragma omp barrier
    trap.run([&] {
      std::uint32_t sum = 0;
      for (std::size_t b = bucket_first; b < bucket_last; ++b)
        for (std::size_t u = 0; u < parts; ++u) sum += cursor_[u * buckets + b];
      part_sums_[part + 1] = sum;
    });
#pragma omp barrier
    trap.run([&] {
      std::uint32_t offset = 0;
      for (std::size_t k = 0; k <= part; ++k) offset += part_sums_[k];
      for (std::size_t b = bucket_first; b < bucket_last; ++b) {
        start_[b] = offset;
        for (std::size_t u = 0; u < parts; ++u) {
          const std::uint32_t count = cursor_[u * buckets + b];
          cursor_[u * buckets + b] = offset;
          offset += count;
        }
      }
    });
#pragma omp barrier
    trap.run([&] {
      std::uint32_t* cursor = cursor_.data() + part * buckets;
      with_density([&](auto dense) {
        for (std::size_t i = first; i < last; ++i) {
          const std::uint64_t key = key_in_[i];
          const std::uint32_t slot = cursor[bucket_index<dense()>(key)]++;
          order_[slot] = static_cast<std::uint32_t>(i);
          keys_[slot] = key;
        }
      });
      start_[buckets] = static_cast<std::uint32_t>(n);
    });
#pragma omp barrier
    // Each bucket sorted by key (a row's cells in order; a hashed bucket's rows apart), and its
    // runs listed by this thread, then copied to runs_ after the runs of the parts before.
    trap.run([&] {
      std::vector<Run>& runs = part_runs_[part];
      runs.clear();
      for (std::size_t b = bucket_first; b < bucket_last; ++b) {
        const std::uint32_t begin = start_[b], end = start_[b + 1];
        sort_slots(begin, end);
        bucket_run_[b] = static_cast<std::uint32_t>(runs.size());
        for (std::uint32_t s = begin; s < end;) {
          std::uint32_t e = s + 1;
          while (e < end && keys_[e] == keys_[s]) ++e;
          runs.push_back({keys_[s], s, e});
          s = e;
        }
      }
      part_sums_[part + 1] = static_cast<std::uint32_t>(runs.size());
    });
#pragma omp barrier
#pragma omp single
    trap.run([&] {
      for (std::size_t k = 0; k < parts; ++k) part_sums_[k + 1] += part_sums_[k];
      runs_.resize(part_sums_[parts]);
      bucket_run_[buckets] = part_sums_[parts];
    });
    trap.run([&] {
      const std::vector<Run>& runs = part_runs_[part];
      const std::uint32_t run_offset = part_sums_[part];
      for (std::size_t b = bucket_first; b < bucket_last; ++b) bucket_run_[b] += run_offset;
      std::copy(runs.begin(), runs.end(), runs_.begin() + run_offset);
    });
  }
  trap.rethrow();
  // The runs by layer: a dense grid's come in key order, hence in layer order, already.
  layer_runs_.resize(runs_.size());
  for (std::uint32_t r = 0; r < runs_.size(); ++r) layer_runs_[r] = r;
  const auto by_layer = [&](std::uint32_t a, std::uint32_t b) {
    return layer(runs_[a].key) < layer(runs_[b].key);
  };
  if (!dense_) std::stable_sort(layer_runs_.begin(), layer_runs_.end(), by_layer);
  layers_.clear();
  for (std::uint32_t k = 0; k < layer_runs_.size(); ++k) {
    const std::int64_t at = layer(runs_[layer_runs_[k]].key);
    if (layers_.empty() || layers_.back().layer != at) {
      if (!layers_.empty()) layers_.back().last = k;
      layers_.push_back({at, k, k});
    }
  }
  if (!layers_.empty()) layers_.back().last = static_cast<std::uint32_t>(layer_runs_.size());
}

void SpatialHash::sort_slots(std::uint32_t first, std::uint32_t last) {
  // Stable, by key. Buckets come almost sorted and small: insertion sort; a long unsorted
  // one (a first build from random input, say) gets a merge sort.
  constexpr std::uint32_t kInsertionMax = 128;
  if (last - first > kInsertionMax) {
    if (std::is_sorted(keys_.begin() + first, keys_.begin() + last)) return;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> mixed;
    for (std::uint32_t s = first; s < last; ++s) mixed.emplace_back(keys_[s], order_[s]);
    std::stable_sort(mixed.begin(), mixed.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::uint32_t s = first; s < last; ++s) {
      keys_[s] = mixed[s - first].first;
      order_[s] = mixed[s - first].second;
    }
    return;
  }
  for (std::uint32_t s = first + 1; s < last; ++s) {
    const std::uint64_t key = keys_[s];
    if (keys_[s - 1] <= key) continue;
    const std::uint32_t index = order_[s];
    std::uint32_t t = s;
    for (; t > first && keys_[t - 1] > key; --t) {
      keys_[t] = keys_[t - 1];
      order_[t] = order_[t - 1];
    }
    keys_[t] = key;
    order_[t] = index;
  }
}

SpatialHash::Range SpatialHash::slots_up_to(const Run* run, const Run* end, std::uint64_t to) {
  if (run == end || run->key > to) return {0, 0};
  Range range{run->first, run->last};
  for (++run; run < end && run->key <= to; ++run) range.second = run->last;
  return range;
}

SpatialHash::Range SpatialHash::cell_slots(std::uint64_t key) const {
  const std::uint64_t b = bucket_index(key);
  const Run* run = runs_.data() + bucket_run_[b];
  const Run* end = runs_.data() + bucket_run_[b + 1];
  run = std::lower_bound(run, end, key, [](const Run& r, std::uint64_t k) { return r.key < k; });
  return slots_up_to(run, end, key);
}

std::array<std::int64_t, 3> SpatialHash::cell_of(const Vec3& p) const {
  const CellOf c(*this);
  return {static_cast<std::int64_t>(c(p, 0)), static_cast<std::int64_t>(c(p, 1)),
          static_cast<std::int64_t>(c(p, 2))};
}

int SpatialHash::ForwardWalk::ranges(std::uint64_t key, std::span<Range> out) {
  const SpatialHash& h = *hash_;
  const std::uint64_t row = key & ~kAxisMask, x = key & kAxisMask;
  // The cells after (x, y, z): x + 1 in its row, the row y + 1 of its plane, the plane z + 1.
  struct Row {
    std::int64_t dy, dz;
  };
  constexpr std::array<Row, kMaxForwardRanges> kRows{{{0, 0}, {1, 0}, {-1, 1}, {0, 1}, {1, 1}}};
  if (row != row_ || x < x_) {  // a new row (or a step back): start each forward row over
    const auto [cx, y, z] = unpack(key);
    for (std::size_t r = 0; r < kRows.size(); ++r) {
      const std::int64_t cy = y + kRows[r].dy, cz = z + kRows[r].dz;
      row_key_[r] = ~std::uint64_t{0};
      at_[r] = end_[r] = nullptr;
      if (cy < 0 || cy >= h.dims_[1] || cz < 0 || cz >= h.dims_[2]) continue;
      row_key_[r] = pack(std::int64_t{0}, cy, cz);
      const std::uint64_t b = h.bucket_index(row_key_[r]);
      at_[r] = h.runs_.data() + h.bucket_run_[b];
      end_[r] = h.runs_.data() + h.bucket_run_[b + 1];
    }
    row_ = row;
  }
  x_ = x;
  const std::uint64_t last_x = static_cast<std::uint64_t>(h.dims_[0] - 1);
  int count = 0;
  for (std::size_t r = 0; r < kRows.size(); ++r) {
    if (row_key_[r] == ~std::uint64_t{0}) continue;
    const std::uint64_t x0 = r == 0 ? x + 1 : (x > 0 ? x - 1 : 0);
    const std::uint64_t x1 = std::min(last_x, x + 1);
    if (x0 > x1) continue;
    // The cells x0 to x1 of the row (slots_up_to()); the next cell's start no earlier.
    const std::uint64_t from = row_key_[r] | x0, to = row_key_[r] | x1;
    const Run* run = at_[r];
    const Run* end = end_[r];
    while (run < end && run->key < from) ++run;
    at_[r] = run;
    const Range range = slots_up_to(run, end, to);
    if (range.first < range.second) out[static_cast<std::size_t>(count++)] = range;
  }
  return count;
}

template <class Visit>
bool SpatialHash::visit_ring(const std::array<std::int64_t, 3>& c, std::int64_t ring,
                             Visit&& visit) const {
  bool any = false;
  const std::int64_t z0 = std::max<std::int64_t>(0, c[2] - ring);
  const std::int64_t z1 = std::min(dims_[2] - 1, c[2] + ring);
  const std::int64_t y0 = std::max<std::int64_t>(0, c[1] - ring);
  const std::int64_t y1 = std::min(dims_[1] - 1, c[1] + ring);
  const std::int64_t x0 = std::max<std::int64_t>(0, c[0] - ring);
  const std::int64_t x1 = std::min(dims_[0] - 1, c[0] + ring);
  for (std::int64_t z = z0; z <= z1; ++z)
    for (std::int64_t y = y0; y <= y1; ++y) {
      const bool inner_zy = std::abs(z - c[2]) < ring && std::abs(y - c[1]) < ring;
      // On rows strictly inside the ring only the two end cells belong to it.
      const std::int64_t step = inner_zy ? std::max<std::int64_t>(1, 2 * ring) : 1;
      for (std::int64_t x = inner_zy ? c[0] - ring : x0; x <= x1; x += step) {
        if (x < x0) continue;
        any = true;
        visit(pack(x, y, z));
      }
    }
  return any;
}

std::pair<std::int64_t, double> SpatialHash::nearest(const Vec3& p, std::span<const Vec3> points,
                                                     std::int64_t skip) const {
  std::int64_t best = -1;
  double best_d2 = std::numeric_limits<double>::infinity();
  if (order_.empty()) return {best, best_d2};
  const auto c = cell_of(p);
  auto visit = [&](std::uint64_t key) {
    const auto [b, e] = cell_slots(key);
    for (std::uint32_t s = b; s < e; ++s) {
      const std::int64_t i = order_[s];
      if (i == skip) continue;
      const double d2 = (points[i] - p).squaredNorm();
      if (d2 < best_d2 || (d2 == best_d2 && i < best)) {
        best_d2 = d2;
        best = i;
      }
    }
  };
  // Every point in ring r is at least r - 1 cell edges away from p, so once the best distance
  // is below that the search is complete. Far-apart sparse points would make rings expensive: after
  // a few empty rings fall back to a linear scan.
  const std::int64_t max_ring = std::max({dims_[0], dims_[1], dims_[2]});
  for (std::int64_t ring = 0; ring <= max_ring; ++ring) {
    if (best >= 0 && std::sqrt(best_d2) <= static_cast<double>(ring - 1) * cell_) break;
    if (ring > 8 && best < 0) {
      for (std::size_t i = 0; i < points.size(); ++i) {
        if (static_cast<std::int64_t>(i) == skip) continue;
        const double d2 = (points[i] - p).squaredNorm();
        if (d2 < best_d2) {
          best_d2 = d2;
          best = static_cast<std::int64_t>(i);
        }
      }
      break;
    }
    if (!visit_ring(c, ring, visit)) break;
  }
  return {best, std::sqrt(best_d2)};
}

std::vector<std::uint32_t> SpatialHash::k_nearest(const Vec3& p, std::span<const Vec3> points,
                                                  std::size_t k, double reach) const {
  std::vector<std::pair<double, std::uint32_t>> found;
  if (order_.empty() || k == 0) return {};
  k = std::min(k, order_.size());
  const auto c = cell_of(p);
  auto visit = [&](std::uint64_t key) {
    const auto [b, e] = cell_slots(key);
    for (std::uint32_t s = b; s < e; ++s)
      found.emplace_back((points[order_[s]] - p).squaredNorm(), order_[s]);
  };
  const std::int64_t max_ring = std::max({dims_[0], dims_[1], dims_[2]});
  for (std::int64_t ring = 0; ring <= max_ring; ++ring) {
    if (found.size() >= k) {
      std::nth_element(found.begin(), found.begin() + static_cast<std::ptrdiff_t>(k - 1),
                       found.end());
      if (std::sqrt(found[k - 1].first) <= static_cast<double>(ring - 1) * cell_) break;
    }
    // Every point within reach is in the rings visited so far.
    if (static_cast<double>(ring - 1) * cell_ > reach) break;
    if (!visit_ring(c, ring, visit)) break;
  }
  std::sort(found.begin(), found.end());
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < std::min(k, found.size()) && found[i].first <= reach * reach; ++i)
    out.push_back(found[i].second);
  return out;
}

}  // namespace zeroset::detail
