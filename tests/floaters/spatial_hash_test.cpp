// The floaters' spatial hash: cells as runs of slots, and the forward halves of the 3×3×3
// blocks around them, checked against brute force on a dense grid and on a hashed one.
#include "spatial_hash_detail.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numeric>
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

// n points in two such slabs at opposite corners of the box [-1, 1]³: with small cells, far
// more rows of cells than points, so the rows are hashed.
std::vector<Vec3> far_apart_points(std::size_t n, std::uint64_t seed, double size) {
  std::vector<Vec3> points = random_points(n, seed, size);
  for (std::size_t i = 0; i < n; ++i) points[i] += Vec3::Constant(i % 2 ? 0.9 : -0.9);
  return points;
}

// Every pair closer than a cell edge is listed exactly once when each cell lists its later
// floaters and its forward ranges, which lie in its own layer or the next.
void expect_forward_ranges_list_each_pair_once(const std::vector<Vec3>& points, double cell,
                                               bool dense, int threads = 1) {
  const Box3 box{Vec3(-1, -1, -1), Vec3(1, 1, 1)};
  SpatialHash hash;
  hash.build(points, box, cell, threads);
  ASSERT_EQ(hash.dense(), dense);
  const auto order = hash.order();
  std::vector<std::uint32_t> run_of(points.size());
  for (std::uint32_t r = 0; r < hash.runs().size(); ++r)
    for (std::uint32_t s = hash.runs()[r].first; s < hash.runs()[r].last; ++s) run_of[s] = r;
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> listed;  // by input indices, lower first
  // In slot order, as the pair pass walks a layer's runs (a hashed grid's rows come in no
  // order: the walk starts over on each).
  SpatialHash::ForwardWalk walk(hash);
  using Ranges = std::vector<SpatialHash::Range>;
  std::vector<Ranges> walked;
  for (const SpatialHash::Run& run : hash.runs()) {
    std::array<SpatialHash::Range, SpatialHash::kMaxForwardRanges> ranges;
    const int count = walk.ranges(run.key, ranges);
    walked.emplace_back(ranges.begin(), ranges.begin() + count);
    for (std::uint32_t s = run.first; s < run.last; ++s) {
      std::vector<std::uint32_t> partners;
      for (std::uint32_t t = s + 1; t < run.last; ++t) partners.push_back(t);
      for (int r = 0; r < count; ++r) {
        ASSERT_LT(ranges[r].first, ranges[r].second);
        for (std::uint32_t t = ranges[r].first; t < ranges[r].second; ++t) {
          const std::int64_t dz =
              SpatialHash::layer(hash.runs()[run_of[t]].key) - SpatialHash::layer(run.key);
          ASSERT_TRUE(dz == 0 || dz == 1) << "a forward cell " << dz << " layers away";
          ASSERT_NE(run_of[t], run_of[s]);
          partners.push_back(t);
        }
      }
      for (std::uint32_t t : partners) {
        const auto a = order[s], b = order[t];
        ++listed[{std::min(a, b), std::max(a, b)}];
      }
    }
  }
  for (const auto& [pair, times] : listed) ASSERT_EQ(times, 1) << "a pair listed twice";
  // Cells in any other order get the same ranges (the walk starts its rows over on a step
  // back).
  std::vector<std::uint32_t> shuffled(hash.runs().size());
  std::iota(shuffled.begin(), shuffled.end(), 0u);
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(1));
  SpatialHash::ForwardWalk jumping(hash);
  for (std::uint32_t r : shuffled) {
    std::array<SpatialHash::Range, SpatialHash::kMaxForwardRanges> ranges;
    const int count = jumping.ranges(hash.runs()[r].key, ranges);
    ASSERT_EQ(Ranges(ranges.begin(), ranges.begin() + count), walked[r]);
  }
  // The layers list every run once, in increasing layer order, runs in slot order within one.
  std::vector<int> seen(hash.runs().size(), 0);
  for (std::size_t l = 0; l < hash.layers().size(); ++l) {
    const SpatialHash::Layer& layer = hash.layers()[l];
    ASSERT_LT(layer.first, layer.last);
    if (l > 0) {
      ASSERT_LT(hash.layers()[l - 1].layer, layer.layer);
    }
    for (std::uint32_t k = layer.first; k < layer.last; ++k) {
      const std::uint32_t r = hash.layer_runs()[k];
      ASSERT_EQ(SpatialHash::layer(hash.runs()[r].key), layer.layer);
      if (k > layer.first) {
        ASSERT_LT(hash.layer_runs()[k - 1], r);
      }
      ++seen[r];
    }
  }
  for (int times : seen) ASSERT_EQ(times, 1) << "a run in no layer or in two";
  std::size_t pairs = 0;
  for (std::uint32_t a = 0; a < points.size(); ++a)
    for (std::uint32_t b = a + 1; b < points.size(); ++b)
      if ((points[a] - points[b]).norm() < cell) {
        ASSERT_TRUE(listed.contains({a, b}))
            << "a pair at " << (points[a] - points[b]).norm() / cell << " cells is missing";
        ++pairs;
      }
  EXPECT_GE(pairs, points.size() / 4);  // there are pairs to check
}

TEST(SpatialHash, ForwardRangesListEveryNeighbourPairOnceOnADenseGrid) {
  expect_forward_ranges_list_each_pair_once(random_points(2000, 4), 0.1, true);
}

TEST(SpatialHash, ForwardRangesListEveryNeighbourPairOnceOnAHashedGrid) {
  expect_forward_ranges_list_each_pair_once(far_apart_points(2000, 5, 0.06), 0.006, false);
}

TEST(SpatialHash, OrderIsStableAndTheSameOnAnyNumberOfThreads) {
  // Duplicated points share a cell and must keep their input order; from 4,096 points on the
  // sort runs in parallel, in as many parts as there are threads.
  std::vector<Vec3> points = far_apart_points(6000, 3, 0.5);
  points.insert(points.end(), points.begin(), points.begin() + 2000);
  const Box3 box{Vec3(-1, -1, -1), Vec3(1, 1, 1)};
  for (double cell : {0.05, 0.002}) {
    SCOPED_TRACE(cell);
    const bool dense = cell == 0.05;
    SpatialHash one;
    one.build(points, box, cell, 1);
    for (const SpatialHash::Run& run : one.runs())
      for (std::uint32_t s = run.first + 1; s < run.last; ++s)
        ASSERT_LT(one.order()[s - 1], one.order()[s]);
    ASSERT_EQ(one.dense(), dense);
    if (dense) {  // a dense grid: its cells follow each other in key order
      const auto runs = one.runs();
      for (std::size_t r = 1; r < runs.size(); ++r) ASSERT_LT(runs[r - 1].key, runs[r].key);
    }
    for (int threads : {2, 3}) {
      SCOPED_TRACE(threads);
      SpatialHash many;
      many.build(points, box, cell, threads);
      ASSERT_TRUE(std::equal(one.order().begin(), one.order().end(), many.order().begin(),
                             many.order().end()));
      expect_forward_ranges_list_each_pair_once(points, cell, dense, threads);
    }
  }
}

TEST(SpatialHash, AnyRegionAndAnyCoordinatesGiveEveryPointOneSlot) {
  // Points off the region, infinite or NaN coordinates, and regions that are inverted, flat
  // or infinite: every point still gets exactly one slot in one run, and close finite points
  // are still listed as pairs.
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<Vec3> points = random_points(500, 6);
  points.push_back(Vec3(kInf, 0, 0));
  points.push_back(Vec3(0, -kInf, 0));
  points.push_back(Vec3(0, 0, std::numeric_limits<double>::quiet_NaN()));
  points.push_back(Vec3(1e300, -1e300, 5));
  const Box3 regions[] = {{Vec3(-1, -1, -1), Vec3(1, 1, 1)},
                          {Vec3(1, 1, 1), Vec3(-1, -1, -1)},
                          {Vec3(-1, -1, 0), Vec3(1, 1, 0)},
                          {Vec3::Constant(-kInf), Vec3::Constant(kInf)},
                          {Vec3(0.2, 0.2, 0.2), Vec3(0.3, 0.3, 0.3)}};
  for (const Box3& region : regions) {
    SCOPED_TRACE(testing::Message() << region.lo.transpose() << " .. " << region.hi.transpose());
    SpatialHash hash;
    hash.build(points, region, 0.1);
    std::vector<int> slots(points.size(), 0);
    for (const SpatialHash::Run& run : hash.runs())
      for (std::uint32_t s = run.first; s < run.last; ++s) ++slots[hash.order()[s]];
    for (int times : slots) ASSERT_EQ(times, 1);
    const auto [j, d] = hash.nearest(points[0], points, 0);
    ASSERT_GE(j, 0);
    for (std::size_t i = 1; i < 500; ++i) ASSERT_LE(d, (points[i] - points[0]).norm());
  }
}

}  // namespace
}  // namespace zeroset::detail
