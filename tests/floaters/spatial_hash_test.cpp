// The floaters' spatial hash: cells as runs of slots, and the 3×3×3 blocks around them, checked
// against brute force on a dense grid and on a hashed one.
#include "spatial_hash_detail.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace zeroset::detail {
namespace {

// n points in a slab of half-width `size` (a third of that in z) around the origin.
std::vector<Vec3> random_points(std::size_t n, std::uint64_t seed, double size = 1) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-size, size);
  std::vector<Vec3> points(n);
  for (Vec3& p : points) p = Vec3(u(rng), u(rng), 0.3 * u(rng));
  return points;
}

// Every pair closer than a cell edge lies in one block, whose ranges do not overlap and hold
// nothing farther than the block reaches.
void expect_blocks_cover_neighbours(const std::vector<Vec3>& points, double cell, int threads) {
  const Box3 box{Vec3(-1, -1, -1), Vec3(1, 1, 1)};
  SpatialHash hash;
  hash.build(points, box, cell, threads);
  const auto order = hash.order();
  ASSERT_EQ(order.size(), points.size());
  std::vector<std::uint32_t> slot_of(points.size());
  for (std::size_t s = 0; s < order.size(); ++s) slot_of[order[s]] = static_cast<std::uint32_t>(s);
  std::size_t covered = 0;
  for (const SpatialHash::Run& run : hash.runs()) {
    std::array<SpatialHash::Range, SpatialHash::kMaxBlockRanges> ranges;
    const int count = hash.block_ranges(run.key, ranges);
    std::vector<bool> in_block(points.size(), false);
    for (int r = 0; r < count; ++r) {
      ASSERT_LT(ranges[r].first, ranges[r].second);
      for (std::uint32_t s = ranges[r].first; s < ranges[r].second; ++s) {
        ASSERT_FALSE(in_block[s]) << "ranges overlap";
        in_block[s] = true;
      }
    }
    for (std::uint32_t s = run.first; s < run.last; ++s) {
      const Vec3& p = points[order[s]];
      for (std::size_t j = 0; j < points.size(); ++j) {
        const double d = (points[j] - p).norm();
        if (d < cell) {
          ASSERT_TRUE(in_block[slot_of[j]]) << "a point at " << d / cell << " cells is missing";
          covered += j != order[s];
        }
        if (in_block[slot_of[j]]) {
          ASSERT_LT(d, 2 * std::sqrt(3.0) * cell * 1.0001);
        }
      }
    }
  }
  EXPECT_GT(covered, points.size() / 4);  // there are pairs to check
}

TEST(SpatialHash, BlocksHoldEveryNeighbourOnADenseGrid) {
  expect_blocks_cover_neighbours(random_points(3000, 1), 0.1, 1);
}

TEST(SpatialHash, BlocksHoldEveryNeighbourOnAHashedGrid) {
  // Tiny cells over the unit box: far more cells than points, so cell keys are hashed.
  expect_blocks_cover_neighbours(random_points(3000, 2, 0.04), 0.004, 1);
}

TEST(SpatialHash, OrderIsStableAndTheSameOnAnyNumberOfThreads) {
  // Duplicated points share a cell and must keep their input order; from 4,096 points on the
  // sort runs in parallel.
  std::vector<Vec3> points = random_points(6000, 3);
  points.insert(points.end(), points.begin(), points.begin() + 2000);
  const Box3 box{Vec3(-1, -1, -1), Vec3(1, 1, 1)};
  for (double cell : {0.05, 0.002}) {
    SCOPED_TRACE(cell);
    SpatialHash one, two;
    one.build(points, box, cell, 1);
    two.build(points, box, cell, 2);
    ASSERT_TRUE(std::equal(one.order().begin(), one.order().end(), two.order().begin(),
                           two.order().end()));
    for (const SpatialHash::Run& run : one.runs())
      for (std::uint32_t s = run.first + 1; s < run.last; ++s)
        ASSERT_LT(one.order()[s - 1], one.order()[s]);
    expect_blocks_cover_neighbours(points, cell, 2);
  }
}

}  // namespace
}  // namespace zeroset::detail
