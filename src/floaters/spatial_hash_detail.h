#pragma once
// A uniform grid over a box, rebuilt in O(n) by a counting sort of point indices by row of
// cells, then by cell within each row, so the points of one cell occupy consecutive slots and
// the cells of one row follow each other. Small grids index their rows directly; large ones
// (tiny cells over a big box) hash rows into 2^k buckets, so memory stays O(n) whatever the
// cell size.
// Private to the floaters module.
#include <algorithm>
#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "rng_detail.h"
#include "zeroset/types.h"

namespace zeroset::detail {

class SpatialHash {
 public:
  /// Sorts `points` into cubic cells of edge `cell` laid over `region` (points outside it fall
  /// into the border cells; an axis on which the region is empty, inverted or not finite gets
  /// one cell). Cell keys
  /// order the cells along the axis with the most cells last (most significant): the layers
  /// of ForwardWalk::ranges(). The edge is enlarged when an axis would need more than 2^20 cells,
  /// and when it is not a positive finite number. Stable: equal cells keep input order.
  /// Parts run on up to `threads` OpenMP threads (from 4,096 points on); the result does not
  /// depend on how many.
  void build(std::span<const Vec3> points, const Box3& region, double cell, int threads = 1);

  /// Whether rows of cells are indexed directly (else hashed into buckets).
  bool dense() const { return dense_; }

  /// Input indices in sorted order ("slots").
  std::span<const std::uint32_t> order() const { return order_; }

  /// A cell with points: its key and the slots [first, last) of its points.
  struct Run {
    std::uint64_t key;
    std::uint32_t first;
    std::uint32_t last;
  };
  /// Every occupied cell once, in slot order.
  std::span<const Run> runs() const { return runs_; }

  /// A range [first, last) of slots.
  using Range = std::pair<std::uint32_t, std::uint32_t>;
  /// Most slot ranges ForwardWalk::ranges() writes.
  static constexpr int kMaxForwardRanges = 5;
  /// Lists the forward ranges of one cell after another. Cheapest when the cells come in key
  /// order, as the runs of a layer do: it walks along each of the five rows instead of
  /// searching it. Any order gives the right ranges. Valid until the hash is rebuilt.
  class ForwardWalk {
   public:
    explicit ForwardWalk(const SpatialHash& hash) : hash_(&hash) {}
    /// Slot ranges holding the points of the 13 cells of the 3×3×3 block around cell `key`
    /// that come after it in key order: every pair of neighbouring cells once, seen from the
    /// one that comes first. One range per row of cells (5 rows); empty ranges are left out.
    /// Returns how many were written to `out` (kMaxForwardRanges long).
    int ranges(std::uint64_t key, std::span<Range> out);

   private:
    const SpatialHash* hash_;
    std::uint64_t row_ = ~std::uint64_t{0};  // the last cell's row (its key without x)
    std::uint64_t x_ = 0;                    // and its x
    // Per forward row: its key without x (~0: no such row), and its runs not yet passed.
    std::array<std::uint64_t, kMaxForwardRanges> row_key_{};
    std::array<const Run*, kMaxForwardRanges> at_{}, end_{};
  };
  /// The layer of cell `key`: its coordinate along the key's most significant axis, which
  /// ForwardWalk::ranges() reaches at most one beyond.
  static std::int64_t layer(std::uint64_t key) { return unpack(key)[2]; }
  /// An occupied layer of cells: its coordinate, and its runs: runs()[layer_runs()[k]] for k
  /// in [first, last).
  struct Layer {
    std::int64_t layer;
    std::uint32_t first, last;
  };
  /// Every occupied layer once, in increasing order.
  std::span<const Layer> layers() const { return layers_; }
  /// Indices into runs(), grouped by layer (see layers()), in slot order within each.
  std::span<const std::uint32_t> layer_runs() const { return layer_runs_; }

  /// The point nearest to p among those built, skipping input index `skip` (pass -1 to skip
  /// none): its input index and distance, or {-1, +∞} when there is none. `points` must be the
  /// span given to build().
  std::pair<std::int64_t, double> nearest(const Vec3& p, std::span<const Vec3> points,
                                          std::int64_t skip) const;
  /// Input indices of the k points nearest to p (fewer when there are fewer), nearest first;
  /// only points within `reach` of p (the search ends there: bounded work far from the points).
  std::vector<std::uint32_t> k_nearest(
      const Vec3& p, std::span<const Vec3> points, std::size_t k,
      double reach = std::numeric_limits<double>::infinity()) const;

 private:
  static constexpr int kBits = 21;
  static constexpr std::uint64_t kAxisMask = (std::uint64_t{1} << kBits) - 1;

  // Lays the grid over `region` for `points` points: origin, cell, axes, dimensions and
  // whether it is dense; returns the number of buckets.
  std::size_t lay_grid(const Box3& region, double cell, std::size_t points);
  // A point's cell coordinates along the key's axes, with the grid's constants at hand.
  struct CellOf {
    explicit CellOf(const SpatialHash& h)
        : axis(h.axis_),
          origin{h.origin_[h.axis_[0]], h.origin_[h.axis_[1]], h.origin_[h.axis_[2]]},
          inv_cell(h.inv_cell_),
          limit(h.limit_) {}
    std::uint64_t operator()(const Vec3& p, std::size_t k) const {
      // Clamped before converting: a point outside the box (or a huge coordinate) must not
      // overflow the integer; a NaN one goes to cell 0.
      const double t = (p[axis[k]] - origin[k]) * inv_cell;
      return static_cast<std::uint64_t>(std::min(limit[k], std::max(0.0, t)));
    }
    std::uint64_t key(const Vec3& p) const {
      return pack((*this)(p, 0), (*this)(p, 1), (*this)(p, 2));
    }
    std::array<int, 3> axis;
    std::array<double, 3> origin;
    double inv_cell;
    std::array<double, 3> limit;
  };
  std::array<std::int64_t, 3> cell_of(const Vec3& p) const;
  static std::uint64_t pack(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
    return x | (y << kBits) | (z << (2 * kBits));
  }
  static std::uint64_t pack(std::int64_t x, std::int64_t y, std::int64_t z) {
    return static_cast<std::uint64_t>(x) | (static_cast<std::uint64_t>(y) << kBits) |
           (static_cast<std::uint64_t>(z) << (2 * kBits));
  }
  static std::array<std::int64_t, 3> unpack(std::uint64_t key) {
    return {static_cast<std::int64_t>(key & kAxisMask),
            static_cast<std::int64_t>((key >> kBits) & kAxisMask),
            static_cast<std::int64_t>(key >> (2 * kBits))};
  }
  // The bucket of cell `key`'s row, in a dense grid or a hashed one.
  template <bool kDense>
  std::uint64_t bucket_index(std::uint64_t key) const {
    if constexpr (kDense)
      return ((key >> kBits) & kAxisMask) +
             static_cast<std::uint64_t>(dims_[1]) * (key >> (2 * kBits));
    else
      return mix64(key & ~kAxisMask) & mask_;
  }
  std::uint64_t bucket_index(std::uint64_t key) const {
    return dense_ ? bucket_index<true>(key) : bucket_index<false>(key);
  }
  // Calls f(std::true_type) on a dense grid, f(std::false_type) on a hashed one.
  template <class F>
  void with_density(F&& f) const {
    if (dense_)
      f(std::true_type{});
    else
      f(std::false_type{});
  }
  // Sorts slots [first, last) by key, stably.
  void sort_slots(std::uint32_t first, std::uint32_t last);
  // The slots of `run` and of the runs after it up to cell `to`, within one bucket's runs
  // [run, end): a bucket's runs are in key order and a row's keys are consecutive numbers, so
  // the cells from run's to `to` of one row are consecutive runs (empty when run is past `to`).
  static Range slots_up_to(const Run* run, const Run* end, std::uint64_t to);
  // Slots of the points in cell `key` (empty when there are none).
  Range cell_slots(std::uint64_t key) const;
  // Visits the cells at Chebyshev distance `ring` from `c`; returns false when none exists.
  template <class Visit>
  bool visit_ring(const std::array<std::int64_t, 3>& c, std::int64_t ring, Visit&& visit) const;

  Vec3 origin_ = Vec3::Zero();
  // The world axes of the key's three coordinates, least significant first.
  std::array<int, 3> axis_{0, 1, 2};
  double cell_ = 1;
  double inv_cell_ = 1;
  std::array<std::int64_t, 3> dims_{1, 1, 1};  // cells along the key's coordinates
  std::array<double, 3> limit_{0, 0, 0};       // dims_ - 1
  bool dense_ = true;
  std::uint64_t mask_ = 0;
  std::vector<std::uint32_t> start_;       // bucket -> first slot; size buckets + 1
  std::vector<std::uint32_t> bucket_run_;  // bucket -> first run; size buckets + 1
  std::vector<std::uint32_t> order_;       // slot -> input index
  std::vector<std::uint64_t> keys_;        // slot -> cell key
  std::vector<Run> runs_;
  std::vector<Layer> layers_;
  std::vector<std::uint32_t> layer_runs_;
  // build() scratch, kept to avoid reallocation: each point's key, each part's cursor per
  // bucket, sums over parts, each part's runs.
  std::vector<std::uint64_t> key_in_;
  std::vector<std::uint32_t> cursor_;
  std::vector<std::uint32_t> part_sums_;
  std::vector<std::vector<Run>> part_runs_;
};

}  // namespace zeroset::detail
