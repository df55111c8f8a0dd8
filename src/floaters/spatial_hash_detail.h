#pragma once
// A uniform grid over a box, rebuilt in O(n) by a counting sort of point indices by cell, so
// the points of one cell occupy consecutive slots. Small grids index their cells directly
// (cells of one x-row follow each other in memory); large ones (tiny cells over a big box)
// hash cell keys into 2^k buckets, so memory stays O(n) whatever the cell size.
// Private to the floaters module.
#include <array>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "zeroset/types.h"

namespace zeroset::detail {

class SpatialHash {
 public:
  /// Sorts `points` into cubic cells of edge `cell` laid over the part of `box` they span
  /// (points outside `box` fall into the border cells). Cell keys order the cells along the
  /// axis with the most cells last (most significant): the layers of forward_ranges(). The
  /// edge is enlarged when an axis would need more than 2^20 cells, and when it is not a
  /// positive finite number. Stable: equal cells keep input order.
  /// Parts run on up to `threads` OpenMP threads (from 4,096 points on); the result does not
  /// depend on how many.
  void build(std::span<const Vec3> points, const Box3& box, double cell, int threads = 1);

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
  /// Most slot ranges forward_ranges() writes.
  static constexpr int kMaxForwardRanges = 13;
  /// Slot ranges holding the points of the 13 cells of the 3×3×3 block around cell `key` that
  /// come after it in key order: every pair of neighbouring cells once, seen from the
  /// one that comes first. One range per row of cells in a dense grid, one per cell in a hashed
  /// one; empty ranges are left out. Returns how many were written to `out`
  /// (kMaxForwardRanges long).
  int forward_ranges(std::uint64_t key, std::span<Range> out) const;
  /// The layer of cell `key`: its coordinate along the key's most significant axis, which
  /// forward_ranges() reaches at most one beyond.
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
  /// Input indices of the k points nearest to p (fewer when there are fewer), nearest first.
  std::vector<std::uint32_t> k_nearest(const Vec3& p, std::span<const Vec3> points,
                                       std::size_t k) const;

 private:
  static constexpr int kBits = 21;
  static constexpr std::uint64_t kAxisMask = (std::uint64_t{1} << kBits) - 1;

  // Lays the grid over the box [lo, hi] within `box` (lo > hi on an axis: all of `box`'s
  // extent there) for `points` points: origin, cell, axes, dimensions and whether it is
  // dense; returns the number of buckets.
  std::size_t lay_grid(const double* lo, const double* hi, const Box3& box, double cell,
                       std::size_t points);
  std::array<std::int64_t, 3> cell_of(const Vec3& p) const;
  static std::uint64_t pack(std::int64_t x, std::int64_t y, std::int64_t z) {
    return static_cast<std::uint64_t>(x) | (static_cast<std::uint64_t>(y) << kBits) |
           (static_cast<std::uint64_t>(z) << (2 * kBits));
  }
  static std::array<std::int64_t, 3> unpack(std::uint64_t key) {
    return {static_cast<std::int64_t>(key & kAxisMask),
            static_cast<std::int64_t>((key >> kBits) & kAxisMask),
            static_cast<std::int64_t>(key >> (2 * kBits))};
  }
  std::uint64_t bucket_index(std::uint64_t key) const;
  // Turns the bucket counts in start_ into each bucket's end slot, in parallel parts: called by
  // every thread of a parallel region (or outside one), with `totals` one longer than the team.
  void prefix_sums(std::vector<std::uint32_t>& totals);
  std::pair<std::uint32_t, std::uint32_t> bucket(std::uint64_t key) const {
    const std::uint64_t b = bucket_index(key);
    return {start_[b], start_[b + 1]};
  }
  // Slots [first, second) of the points in cell `key` (empty when it has none).
  std::pair<std::uint32_t, std::uint32_t> cell_range(std::uint64_t key) const;
  // Visits the cells at Chebyshev distance `ring` from `c`; returns false when none exists.
  template <class Visit>
  bool visit_ring(const std::array<std::int64_t, 3>& c, std::int64_t ring, Visit&& visit) const;

  Vec3 origin_ = Vec3::Zero();
  // The world axes of the key's three coordinates, least significant first.
  std::array<int, 3> axis_{0, 1, 2};
  double cell_ = 1;
  double inv_cell_ = 1;
  std::array<std::int64_t, 3> dims_{1, 1, 1};  // cells along the key's coordinates
  bool dense_ = true;
  std::uint64_t mask_ = 0;
  std::vector<std::uint32_t> start_;  // bucket -> first slot; size buckets + 1
  std::vector<std::uint32_t> order_;  // slot -> input index
  std::vector<std::uint64_t> keys_;   // slot -> cell key
  std::vector<Run> runs_;
  std::vector<Layer> layers_;
  std::vector<std::uint32_t> layer_runs_;
  std::vector<std::uint64_t> key_in_;  // build() scratch, kept to avoid reallocation
  std::vector<std::uint32_t> bucket_in_;
};

}  // namespace zeroset::detail
