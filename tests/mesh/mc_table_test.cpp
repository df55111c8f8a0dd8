#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

#include "mc_table_detail.h"

namespace zeroset::detail {
namespace {

int crossing_edges(int cube_case) {
  int n = 0;
  for (const auto& e : kEdgeCorners) n += ((cube_case >> e[0]) & 1) != ((cube_case >> e[1]) & 1);
  return n;
}

TEST(McTable, EveryCrossingEdgeIsInExactlyOneCycle) {
  for (int c = 0; c < 256; ++c)
    for (int d = 0; d < 64; ++d) {
      const CellPolygons& p = cell_polygons(c, d);
      int total = 0;
      std::array<int, 12> seen{};
      for (int k = 0; k < p.cycle_count; ++k) {
        EXPECT_GE(p.cycle_length[k], 3) << "case " << c;
        total += p.cycle_length[k];
      }
      ASSERT_EQ(total, crossing_edges(c)) << "case " << c;
      for (int k = 0; k < total; ++k) ++seen[p.edges[k]];
      for (int e = 0; e < 12; ++e) {
        EXPECT_LE(seen[e], 1);
        EXPECT_EQ(seen[e] == 1, ((kCrossingEdges[c] >> e) & 1) != 0)
            << "case " << c << " edge " << e;
      }
    }
}

TEST(McTable, ConsecutiveCyclePointsShareAFace) {
  for (int c = 0; c < 256; ++c) {
    const CellPolygons& p = cell_polygons(c, 0);
    int at = 0;
    for (int k = 0; k < p.cycle_count; ++k) {
      const int n = p.cycle_length[k];
      for (int i = 0; i < n; ++i)
        EXPECT_TRUE(edges_share_face(p.edges[at + i], p.edges[at + (i + 1) % n])) << "case " << c;
      at += n;
    }
  }
}

TEST(McTable, ComplementaryCasesHaveReversedCycles) {
  // Swapping inside and outside must give the same segments run backwards (orientation).
  for (int c = 1; c < 255; ++c) {
    if (ambiguous_faces(c)) continue;
    const CellPolygons& p = cell_polygons(c, 0);
    const CellPolygons& q = cell_polygons(255 - c, 0);
    ASSERT_EQ(p.cycle_count, q.cycle_count);
    std::array<int, 12> next_p{}, next_q{};
    next_p.fill(-1), next_q.fill(-1);
    int at = 0;
    for (int k = 0; k < p.cycle_count; ++k) {
      for (int i = 0; i < p.cycle_length[k]; ++i)
        next_p[p.edges[at + i]] = p.edges[at + (i + 1) % p.cycle_length[k]];
      at += p.cycle_length[k];
    }
    at = 0;
    for (int k = 0; k < q.cycle_count; ++k) {
      for (int i = 0; i < q.cycle_length[k]; ++i)
        next_q[q.edges[at + (i + 1) % q.cycle_length[k]]] = q.edges[at + i];
      at += q.cycle_length[k];
    }
    EXPECT_EQ(next_p, next_q) << "case " << c;
  }
}

TEST(McTable, ChordsJoinNeighboursAndPointsOfDifferentFaces) {
  for (int c = 0; c < 256; ++c)
    for (int d = 0; d < 64; ++d) {
      const CellPolygons& p = cell_polygons(c, d);
      int start = 0;
      for (int k = 0; k < p.cycle_count; ++k) {
        const int n = p.cycle_length[k];
        for (int a = 0; a < n; ++a) {
          for (int b = 0; b < n; ++b) {
            const bool allowed = ((p.chords[start + a] >> b) & 1) != 0;
            const bool neighbours = (a + 1) % n == b || (b + 1) % n == a;
            const bool one_face = edges_share_face(p.edges[start + a], p.edges[start + b]);
            EXPECT_EQ(allowed, a != b && (neighbours || !one_face)) << "case " << c;
          }
          EXPECT_EQ(p.chords[start + a] >> n, 0) << "case " << c;  // only points of the cycle
        }
        start += n;
      }
    }
}

TEST(McTable, EveryResolutionOfTheAmbiguousFacesHasItsOwnEntry) {
  const CellPolygons* table = cell_polygon_table();
  for (int c = 0; c < 256; ++c) {
    const int amb = ambiguous_faces(c);
    std::array<int, 64> seen{};
    for (int d = 0; d < 64; ++d) {
      // Bits of faces that are not ambiguous do not matter.
      EXPECT_EQ(&cell_polygons(c, d), &cell_polygons(c, d & amb)) << "case " << c;
      if ((d & ~amb) == 0) ++seen[static_cast<size_t>(ambiguous_rank(c, d))];
    }
    const int resolutions = 1 << std::popcount(static_cast<unsigned>(amb));
    const CellPolygons* first = table + kCaseFirst[static_cast<size_t>(c)];
    const CellPolygons* end = table + kCaseFirst[static_cast<size_t>(c) + 1];
    EXPECT_EQ(end - first, resolutions);
    for (int r = 0; r < 64; ++r)
      EXPECT_EQ(seen[static_cast<size_t>(r)], r < resolutions ? 1 : 0) << "case " << c;
    for (int d = 0; d < 64; ++d) {
      EXPECT_GE(&cell_polygons(c, d), first);
      EXPECT_LT(&cell_polygons(c, d), end);
    }
  }
  EXPECT_EQ(kCellEntries, 656);
}

TEST(McTable, AsymptoticDeciderFollowsTheBilinearSaddle) {
  // The decider must agree with the sign of the bilinear interpolant at its saddle point,
  // and give the same answer for the face seen from either cube (mirror images).
  std::uint64_t state = 12345;
  auto uniform = [&] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(state >> 11) * 0x1.0p-53 * 2 - 1;
  };
  int checked = 0;
  while (checked < 2000) {
    const double v00 = uniform(), v10 = uniform(), v11 = uniform(), v01 = uniform();
    const bool ambiguous =
        (v00 >= 0) == (v11 >= 0) && (v10 >= 0) == (v01 >= 0) && (v00 >= 0) != (v10 >= 0);
    if (!ambiguous) continue;
    const double den = v00 - v10 - v01 + v11;
    const double u = (v00 - v01) / den, v = (v00 - v10) / den;
    const double saddle =
        v00 * (1 - u) * (1 - v) + v10 * u * (1 - v) + v11 * u * v + v01 * (1 - u) * v;
    if (std::abs(saddle) < 1e-9) continue;
    EXPECT_EQ(positive_corners_connected(v00, v10, v11, v01), saddle > 0);
    EXPECT_EQ(positive_corners_connected(v00, v10, v11, v01),
              positive_corners_connected(v10, v00, v01, v11));
    ++checked;
  }
}

}  // namespace
}  // namespace zeroset::detail
