#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "rng_detail.h"
#include "spatial_hash_detail.h"

namespace zeroset::detail {
namespace {
// A dense grid may have this many cells per point before hashing is cheaper in memory.
constexpr std::int64_t kDenseCellsPerPoint = 64;
constexpr std::int64_t kDenseMinCells = 1 << 16;
// Fewer points than this are sorted on one thread.
constexpr std::int64_t kParallelMin = 4096;
}  // namespace

std::size_t SpatialHash::lay_grid(const double* lo, const double* hi, const Box3& box,
                                  double cell, std::size_t points) {
  Vec3 extent;
  for (int k = 0; k < 3; ++k) {
    const double first = lo[k] <= hi[k] ? std::max(lo[k], box.lo[k]) : box.lo[k];
    const double last = lo[k] <= hi[k] ? std::min(hi[k], box.hi[k]) : box.hi[k];
    origin_[k] = std::min(first, last);
    extent[k] = std::max(last - first, 0.0);
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
  // forward_ranges() works across in layers.
  const int major =
      across[2] >= std::max(across[0], across[1]) ? 2 : (across[1] >= across[0] ? 1 : 0);
  axis_ = major == 2   ? std::array{0, 1, 2}
          : major == 1 ? std::array{0, 2, 1}
                       : std::array{1, 2, 0};
  std::int64_t cells = 1;
  for (int k = 0; k < 3; ++k) {
    dims_[k] = across[static_cast<std::size_t>(axis_[k])];
    cells = cells > std::numeric_limits<std::int64_t>::max() / dims_[k]
                ? std::numeric_limits<std::int64_t>::max()
                : cells * dims_[k];
  }
  const auto n = static_cast<std::int64_t>(points);
  dense_ = cells <= std::max(kDenseCellsPerPoint * n, kDenseMinCells);
  if (dense_) return static_cast<std::size_t>(cells);
  const std::size_t buckets =
      std::bit_ceil(static_cast<std::size_t>(std::max<std::int64_t>(2 * n, 16)));
  mask_ = buckets - 1;
  return buckets;
}

void SpatialHash::build(std::span<const Vec3> points, const Box3& box, double cell,
                        int threads) {
  const std::int64_t n = static_cast<std::int64_t>(points.size());
  const int team = n >= kParallelMin ? std::max(threads, 1) : 1;
  keys_.resize(points.size());
  order_.resize(points.size());
  key_in_.resize(points.size());
  bucket_in_.resize(points.size());
  // The grid covers the points' bounding box within `box` (non-finite coordinates do not
  // count), not all of `box`: a surface that lies flat in its box gets few cells across it.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
  std::size_t buckets = 0;
  // Counting sort by bucket: count, prefix sums, then place from the back, each bucket's
  // cursor moving down from its end (stable: equal cells keep input order), which leaves
  // start_[b] at bucket b's first slot. Floaters come kept in cell order, so the counting and
  // placing walk the bucket array almost in order. The bounding box, keys, counts and prefix
  // sums in one parallel region (its threads wake once).
  std::vector<std::uint32_t> totals(static_cast<std::size_t>(team) + 1, 0);
#pragma omp parallel num_threads(team)
  {
#pragma omp for schedule(static) reduction(min : lo[:3]) reduction(max : hi[:3])
    for (std::int64_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        const double v = points[static_cast<std::size_t>(i)][k];
        lo[k] = v < lo[k] ? v : lo[k];
        hi[k] = v > hi[k] ? v : hi[k];
      }
#pragma omp single
    {
      buckets = lay_grid(lo, hi, box, cell, points.size());
      start_.resize(buckets + 1);
    }
#pragma omp for schedule(static)
    for (std::int64_t i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const auto c = cell_of(points[k]);
      key_in_[k] = pack(c[0], c[1], c[2]);
      bucket_in_[k] = static_cast<std::uint32_t>(bucket_index(key_in_[k]));
    }
#pragma omp single
    {
      std::fill(start_.begin(), start_.end(), 0);
      for (std::uint32_t b : bucket_in_) ++start_[b];
    }
    prefix_sums(totals);
  }
  start_[buckets] = buckets > 0 ? start_[buckets - 1] : 0;
  for (std::size_t i = points.size(); i-- > 0;) {
    const std::uint32_t slot = --start_[bucket_in_[i]];
    order_[slot] = static_cast<std::uint32_t>(i);
    keys_[slot] = key_in_[i];
  }
  // A hashed bucket may mix cells: order its slots by key (stably, so equal cells keep input
  // order) to make every cell one run of slots. A dense grid has one cell per bucket already.
  if (!dense_) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> mixed;
    for (std::size_t b = 0; b < buckets; ++b) {
      const std::uint32_t first = start_[b], last = start_[b + 1];
      if (last - first < 2 || std::all_of(keys_.begin() + first, keys_.begin() + last,
                                          [&](std::uint64_t k) { return k == keys_[first]; }))
        continue;
      mixed.clear();
      for (std::uint32_t s = first; s < last; ++s) mixed.emplace_back(keys_[s], order_[s]);
      std::stable_sort(mixed.begin(), mixed.end(),
                       [](const auto& a, const auto& b) { return a.first < b.first; });
      for (std::uint32_t s = first; s < last; ++s) {
        keys_[s] = mixed[s - first].first;
        order_[s] = mixed[s - first].second;
      }
    }
  }
  runs_.clear();
  const auto slots = static_cast<std::uint32_t>(keys_.size());
  for (std::uint32_t s = 0; s < slots;) {
    std::uint32_t e = s + 1;
    while (e < slots && keys_[e] == keys_[s]) ++e;
    runs_.push_back({keys_[s], s, e});
    s = e;
  }
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

void SpatialHash::prefix_sums(std::vector<std::uint32_t>& totals) {
  // In place over the bucket counts start_[0, buckets). A grid may have several buckets per
  // point, so the sums run in contiguous parts, one per thread of the enclosing region: each
  // part's total first, then each part adds the totals before it (integers: the same result
  // whatever the team). totals has one entry more than the team.
  const std::size_t buckets = start_.size() - 1;
#ifdef _OPENMP
  const auto part = static_cast<std::size_t>(omp_get_thread_num());
  const auto parts = static_cast<std::size_t>(omp_get_num_threads());
#else
  const std::size_t part = 0, parts = 1;
#endif
  const std::size_t begin = buckets * part / parts, end = buckets * (part + 1) / parts;
  if (part + 1 < parts) {  // the last part's total is never needed
    std::uint32_t sum = 0;
    for (std::size_t b = begin; b < end; ++b) sum += start_[b];
    totals[part + 1] = sum;
  }
#pragma omp barrier
  std::uint32_t offset = 0;
  for (std::size_t k = 0; k <= part; ++k) offset += totals[k];
  for (std::size_t b = begin; b < end; ++b) start_[b] = offset += start_[b];
}

std::pair<std::uint32_t, std::uint32_t> SpatialHash::cell_range(std::uint64_t key) const {
  auto [first, last] = bucket(key);
  if (dense_) return {first, last};
  while (first < last && keys_[first] != key) ++first;
  std::uint32_t end = first;
  while (end < last && keys_[end] == key) ++end;
  return {first, end};
}

std::array<std::int64_t, 3> SpatialHash::cell_of(const Vec3& p) const {
  std::array<std::int64_t, 3> c;
  for (int k = 0; k < 3; ++k) {
    const int a = axis_[k];
    const double t = (p[a] - origin_[a]) * inv_cell_;
    // Clamp before converting: a point outside the box (or a huge coordinate) must not
    // overflow the integer.
    const double clamped = std::clamp(t, 0.0, static_cast<double>(dims_[k] - 1));
    c[k] = static_cast<std::int64_t>(clamped);
  }
  return c;
}

std::uint64_t SpatialHash::bucket_index(std::uint64_t key) const {
  if (dense_) {
    const auto [x, y, z] = unpack(key);
    return static_cast<std::uint64_t>(x + dims_[0] * (y + dims_[1] * z));
  }
  return mix64(key) & mask_;
}

int SpatialHash::forward_ranges(std::uint64_t key, std::span<Range> out) const {
  const auto [x, y, z] = unpack(key);
  int count = 0;
  auto add = [&](Range r) {
    out[static_cast<std::size_t>(count)] = r;
    count += r.first < r.second;
  };
  // The cells after (x, y, z): x + 1 in its row, the row y + 1 of its plane, the plane z + 1.
  struct Row {
    std::int64_t dy, dz, x0;
  };
  for (const Row row : {Row{0, 0, x + 1}, Row{1, 0, x - 1}, Row{-1, 1, x - 1}, Row{0, 1, x - 1},
                        Row{1, 1, x - 1}}) {
    const std::int64_t cy = y + row.dy, cz = z + row.dz;
    if (cy < 0 || cy >= dims_[1] || cz < 0 || cz >= dims_[2]) continue;
    const std::int64_t x0 = std::max<std::int64_t>(0, row.x0), x1 = std::min(dims_[0] - 1, x + 1);
    if (x0 > x1) continue;
    if (dense_) {
      const auto b = static_cast<std::size_t>(x0 + dims_[0] * (cy + dims_[1] * cz));
      add({start_[b], start_[b + static_cast<std::size_t>(x1 - x0) + 1]});
    } else {
      for (std::int64_t cx = x0; cx <= x1; ++cx) add(cell_range(pack(cx, cy, cz)));
    }
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
    const auto [b, e] = bucket(key);
    for (std::uint32_t s = b; s < e; ++s) {
      if (keys_[s] != key) continue;
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
                                                  std::size_t k) const {
  std::vector<std::pair<double, std::uint32_t>> found;
  if (order_.empty() || k == 0) return {};
  k = std::min(k, order_.size());
  const auto c = cell_of(p);
  auto visit = [&](std::uint64_t key) {
    const auto [b, e] = bucket(key);
    for (std::uint32_t s = b; s < e; ++s)
      if (keys_[s] == key) found.emplace_back((points[order_[s]] - p).squaredNorm(), order_[s]);
  };
  const std::int64_t max_ring = std::max({dims_[0], dims_[1], dims_[2]});
  for (std::int64_t ring = 0; ring <= max_ring; ++ring) {
    if (found.size() >= k) {
      std::nth_element(found.begin(), found.begin() + static_cast<std::ptrdiff_t>(k - 1),
                       found.end());
      if (std::sqrt(found[k - 1].first) <= static_cast<double>(ring - 1) * cell_) break;
    }
    if (!visit_ring(c, ring, visit)) break;
  }
  std::sort(found.begin(), found.end());
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < std::min(k, found.size()); ++i) out.push_back(found[i].second);
  return out;
}

}  // namespace zeroset::detail
