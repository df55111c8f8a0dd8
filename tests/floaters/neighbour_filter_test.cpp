// The neighbour search's single-precision filters: every implementation the build and processor
// offer keeps exactly the points the plain test keeps, and the per-cell box filter keeps every
// point the per-floater filter keeps for any floater in the box.
#include "neighbour_filter_detail.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

namespace zeroset::detail {
namespace {

struct Cloud {
  std::vector<float> x, y, z, cut;  // padded by kFilterPad
  std::vector<SpatialHash::Range> ranges;
};

// Points in [-1, 1]² × [-0.2, 0.2] with thresholds 0.1² to 0.22², and ranges of every length
// from 0 to 19 (many ends inside a group of eight), in increasing order.
Cloud make_cloud(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-1, 1), t(0.01f, 0.05f);
  Cloud c;
  std::uint32_t next = 0;
  for (std::uint32_t len = 0; len < 20; ++len) {
    c.ranges.emplace_back(next, next + len);
    next += len + len % 3;  // gaps between some ranges
  }
  for (std::uint32_t k = 0; k < next + kFilterPad; ++k) {
    c.x.push_back(u(rng));
    c.y.push_back(u(rng));
    c.z.push_back(0.2f * u(rng));
    c.cut.push_back(t(rng));
  }
  return c;
}

std::vector<FilterPath> available_paths() {
  std::vector<FilterPath> paths;
  for (FilterPath p : {FilterPath::kScalar, FilterPath::kSse2, FilterPath::kAvx2})
    if (filter_path_available(p)) paths.push_back(p);
  return paths;
}

TEST(NeighbourFilter, EveryPathKeepsExactlyThePointsWithinTheirThreshold) {
  const Cloud c = make_cloud(5);
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<float> u(-1, 1);
  std::size_t kept_total = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const float px = u(rng), py = u(rng), pz = 0.2f * u(rng), p_cut = 0.03f;
    std::vector<std::uint32_t> expected;
    for (const auto& [first, last] : c.ranges)
      for (std::uint32_t t = first; t < last; ++t) {
        const float dx = px - c.x[t], dy = py - c.y[t], dz = pz - c.z[t];
        if ((dx * dx + dy * dy) + dz * dz < std::max(p_cut, c.cut[t])) expected.push_back(t);
      }
    kept_total += expected.size();
    for (FilterPath path : available_paths()) {
      SCOPED_TRACE(static_cast<int>(path));
      std::vector<std::uint32_t> out(c.x.size() + kFilterPad);
      const std::size_t m = filter_near(path, c.ranges, c.x.data(), c.y.data(), c.z.data(),
                                        c.cut.data(), px, py, pz, p_cut, out.data());
      out.resize(m);
      ASSERT_EQ(out, expected);
    }
  }
  EXPECT_GT(kept_total, 400u);  // the trials do keep points
}

TEST(NeighbourFilter, BoxKeepsWhatAnyFloaterInTheBoxKeeps) {
  const Cloud c = make_cloud(7);
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<float> u(-1, 1), w(0, 0.1f);
  for (int trial = 0; trial < 100; ++trial) {
    const float lo[3] = {u(rng), u(rng), 0.2f * u(rng)};
    const float hi[3] = {lo[0] + w(rng), lo[1] + w(rng), lo[2] + w(rng)};
    std::vector<float> fx, fy, fz, fcut;
    std::uniform_real_distribution<float> unit(0, 1), t(0.01f, 0.05f);
    float reach = 0;
    for (int k = 0; k < 6; ++k) {
      fx.push_back(lo[0] + (hi[0] - lo[0]) * unit(rng));
      fy.push_back(lo[1] + (hi[1] - lo[1]) * unit(rng));
      fz.push_back(lo[2] + (hi[2] - lo[2]) * unit(rng));
      fcut.push_back(t(rng));
      reach = std::max(reach, fcut.back());
    }
    for (FilterPath path : available_paths()) {
      SCOPED_TRACE(static_cast<int>(path));
      std::vector<std::uint32_t> box(c.x.size() + kFilterPad), one(c.x.size() + kFilterPad);
      box.resize(filter_box(path, c.ranges, c.x.data(), c.y.data(), c.z.data(), c.cut.data(), lo,
                            hi, reach, box.data()));
      ASSERT_TRUE(std::is_sorted(box.begin(), box.end()));
      for (std::size_t k = 0; k < fx.size(); ++k) {
        one.resize(c.x.size() + kFilterPad);
        one.resize(filter_near(path, c.ranges, c.x.data(), c.y.data(), c.z.data(), c.cut.data(),
                               fx[k], fy[k], fz[k], fcut[k], one.data()));
        for (std::uint32_t t : one) ASSERT_TRUE(std::binary_search(box.begin(), box.end(), t));
      }
    }
  }
}

TEST(NeighbourFilter, TheBestPathIsAvailable) {
  EXPECT_TRUE(filter_path_available(best_filter_path()));
  EXPECT_TRUE(filter_path_available(FilterPath::kScalar));
}

}  // namespace
}  // namespace zeroset::detail
