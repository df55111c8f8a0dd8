// The triangulation of a cell's cycles: the fast paths for quadrilaterals and pentagons choose
// what the general dynamic programme chooses, and every choice respects the cycle's chords.
#include <gtest/gtest.h>

#include <array>
#include <random>
#include <vector>

#include "cell_triangulation_detail.h"
#include "mc_table_detail.h"

namespace zeroset::detail {
namespace {

using Tri = std::array<int, 3>;

// Every cycle of n points in the case table, as (edges, chords) of its first point.
std::vector<std::pair<const std::uint8_t*, const std::uint16_t*>> table_cycles(int n) {
  std::vector<std::pair<const std::uint8_t*, const std::uint16_t*>> out;
  const CellPolygons* table = cell_polygon_table();
  for (int e = 0; e < kCellEntries; ++e) {
    const CellPolygons& p = table[e];
    int start = 0;
    for (int c = 0; c < p.cycle_count; ++c) {
      if (p.cycle_length[static_cast<size_t>(c)] == n)
        out.emplace_back(&p.edges[static_cast<size_t>(start)],
                         &p.chords[static_cast<size_t>(start)]);
      start += p.cycle_length[static_cast<size_t>(c)];
    }
  }
  return out;
}

// Random points for the 12 cube edges (anywhere in the unit cube: the choice only depends on
// the distances).
std::array<Vec3, 12> random_points(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  std::array<Vec3, 12> p;
  for (Vec3& q : p) q = Vec3(u(rng), u(rng), u(rng));
  return p;
}

// The worst quality of a triangulation (as triangle_quality orders triangles).
double worst(const std::vector<Tri>& tris, const std::array<Vec3, 12>& p) {
  double w = 1e300;
  for (const Tri& t : tris) {
    const Vec3 &a = p[static_cast<size_t>(t[0])], &b = p[static_cast<size_t>(t[1])],
               &c = p[static_cast<size_t>(t[2])];
    w = std::min(
        w, triangle_quality((b - a).squaredNorm(), (c - a).squaredNorm(), (c - b).squaredNorm()));
  }
  return w;
}

// Each triangle side joins neighbours of the cycle or a pair its chords allow.
bool respects_chords(const std::vector<Tri>& tris, const std::uint8_t* edges,
                     const std::uint16_t* chords, int n) {
  auto index = [&](int e) {
    for (int a = 0; a < n; ++a)
      if (edges[a] == e) return a;
    return -1;
  };
  for (const Tri& t : tris)
    for (int k = 0; k < 3; ++k) {
      const int a = index(t[static_cast<size_t>(k)]),
                b = index(t[static_cast<size_t>((k + 1) % 3)]);
      if (a < 0 || b < 0) return false;
      const int lo = std::min(a, b), hi = std::max(a, b);
      if (!((chords[lo] >> hi) & 1)) return false;
    }
  return true;
}

template <class Triangulate>
std::vector<Tri> triangles_of(Triangulate&& triangulate) {
  std::vector<Tri> out;
  triangulate([&](int a, int b, int c) { out.push_back({a, b, c}); });
  return out;
}

// Calls check(edges, chords, points, fast, general) for 20,000 random point sets on the table's
// cycles of n points: `fast` as the polygonizer triangulates (triangulate_cycle), `general` by
// the dynamic programme for any n (triangulate_polygon).
template <class Check>
void for_random_cycles(int n, std::uint64_t seed, Check&& check) {
  const auto cycles = table_cycles(n);
  ASSERT_FALSE(cycles.empty());
  std::mt19937_64 rng(seed);
  for (int trial = 0; trial < 20000; ++trial) {
    const auto& cycle = cycles[static_cast<size_t>(trial) % cycles.size()];
    const auto& edges = cycle.first;  // names of their own: lambdas capture them
    const auto& chords = cycle.second;
    const std::array<Vec3, 12> p = random_points(rng);
    auto pos = [&](int e) -> const Vec3& { return p[static_cast<size_t>(e)]; };
    const auto fast =
        triangles_of([&](auto emit) { triangulate_cycle(edges, chords, n, pos, emit); });
    const auto general =
        triangles_of([&](auto emit) { triangulate_polygon(edges, chords, n, pos, emit); });
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    ASSERT_EQ(fast.size(), static_cast<size_t>(n - 2));
    ASSERT_TRUE(respects_chords(fast, edges, chords, n));
    check(p, fast, general);
    if (testing::Test::HasFatalFailure()) return;
  }
}

TEST(CellTriangulation, PentagonsAreSplitExactlyAsByTheGeneralProgramme) {
  for_random_cycles(
      5, 11, [](const auto&, const auto& fast, const auto& general) { ASSERT_EQ(fast, general); });
}

TEST(CellTriangulation, QuadrilateralsTakeTheBetterAllowedDiagonal) {
  for_random_cycles(4, 12, [](const auto& p, const auto& fast, const auto& general) {
    // The vector path may round a quality in its last bit differently: equal up to a tie.
    ASSERT_GE(worst(fast, p), worst(general, p) * (1 - 1e-12));
  });
}

}  // namespace
}  // namespace zeroset::detail
