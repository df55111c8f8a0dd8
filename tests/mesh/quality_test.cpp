#include <gtest/gtest.h>

#include <cmath>

#include "mesh_test_support.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"

namespace zeroset {
namespace {

TEST(Quality, EquilateralTriangleHasSixtyDegreesAndRatioOne) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0.5, std::sqrt(3.0) / 2, 0);
  EXPECT_NEAR(triangle_min_angle_deg(a, b, c), 60, 1e-9);
  EXPECT_NEAR(triangle_radius_ratio(a, b, c), 1, 1e-12);
  EXPECT_EQ(triangle_min_angle_deg(a, b, Vec3(2, 0, 0)), 0);
  EXPECT_NEAR(triangle_min_angle_deg(a, b, Vec3(0, 1, 0)), 45, 1e-9);
}

TEST(Quality, HistogramCountsEveryTriangle) {
  const Surface s = test::catalog_surface("sphere");
  const Mesh m = polygonize(s, {.cells = 20});
  const MeshQuality q = measure_quality(m, s);
  long long sum = 0;
  for (long long c : q.min_angle_histogram) sum += c;
  EXPECT_EQ(sum, static_cast<long long>(m.triangle_count()));
  EXPECT_LE(q.percent_below_10, q.percent_below_20);
  EXPECT_LE(q.percent_below_20, q.percent_below_30);
  EXPECT_GT(q.mean_min_angle_deg, 20);
  EXPECT_LT(q.max_residual, 1e-9);
  EXPECT_EQ(q.flipped_triangles, 0u);
}

TEST(Quality, MeasuresDistanceFromEveryKnownNode) {
  const Surface s = test::kummer(1.5);
  const Mesh m = polygonize(s, {.cells = 24});
  const MeshQuality q = measure_quality(m, s);
  ASSERT_EQ(q.singular_points.size(), 16u);
  ASSERT_EQ(q.singular_point_distance.size(), 16u);
  for (double d : q.singular_point_distance) EXPECT_LT(d, 2 * q.mean_edge_length);
  EXPECT_LT(q.max_boundary_clip_value, 1e-9);
}

}  // namespace
}  // namespace zeroset
