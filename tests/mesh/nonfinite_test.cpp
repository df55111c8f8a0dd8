// The polygonizer and the improver where F is undefined (NaN or infinite) on part of the clip:
// no vertex on an edge with an undefined end, no crossing at a pole, no move out of the clip
// or onto an undefined point, and a residual that counts undefined vertices as failures.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "mesh/mesh_test_support.h"
#include "zeroset/expr/field.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/polygonize.h"

namespace zeroset {
namespace {

// 1/x − 1 jumps from −∞ to +∞ at x = 0: a sign change of every x edge there, but no zero.
TEST(PolygonizeNonFinite, APoleMakesNoVertices) {
  const Surface s = test::equation("1/x - 1", Clip::sphere(2));
  for (GridMode mode : {GridMode::kDense, GridMode::kSparse}) {
    PolygonizeStats st;
    const Mesh m = polygonize(s, {.cells = 41, .mode = mode}, &st);
    ASSERT_FALSE(m.positions.empty());
    EXPECT_GT(st.pole_edges, 0);
    for (const Vec3& p : m.positions) {
      ASSERT_GE(std::abs(p.x()), st.cell_size / 2) << p.transpose();
      ASSERT_NEAR(p.x(), 1.0, 1e-9) << p.transpose();
    }
  }
}

// The same with grid nodes on x = 0 (spacing 1/8 from −2), where F = ±∞.
TEST(PolygonizeNonFinite, InfiniteNodesHoldNoVertex) {
  const Surface s = test::equation("1/x - 1", Clip::sphere(2));
  PolygonizeStats st;
  const Mesh m =
      polygonize(s, {.bounds = Box3::cube(2), .cells = 32, .mode = GridMode::kDense}, &st);
  EXPECT_GT(st.nan_samples, 0);
  for (const Vec3& p : m.positions) ASSERT_NEAR(p.x(), 1.0, 1e-9) << p.transpose();
}

// sqrt(x) + y² + z² − 1 is NaN for x < 0: that half holds no surface, whatever the sign test
// would say there; every vertex lies where F is finite, refined or linear.
TEST(PolygonizeNonFinite, VerticesLieWhereFIsFinite) {
  const Surface s = test::equation("sqrt(x) + y^2 + z^2 - 1", Clip::sphere(2));
  Evaluator ev(s.field);
  for (int steps : {12, 0}) {
    for (GridMode mode : {GridMode::kDense, GridMode::kSparse}) {
      PolygonizeStats st;
      const Mesh m = polygonize(s, {.cells = 40, .mode = mode, .refine_steps = steps}, &st);
      ASSERT_FALSE(m.positions.empty());
      EXPECT_GT(st.nan_samples, 0);
      EXPECT_GT(st.undefined_edges, 0);
      EXPECT_GT(st.undefined_triangles, 0);
      for (const Vec3& p : m.positions) {
        ASSERT_GE(p.x(), 0) << p.transpose();
        ASSERT_TRUE(std::isfinite(ev.value(p))) << p.transpose();
      }
    }
  }
}

// A vertex where F is NaN is a failure of the residual, not a vertex left out of it.
TEST(ImproveNonFinite, ResidualCountsUndefinedVertices) {
  const Surface s = test::equation("sqrt(x) + y^2 + z^2 - 1", Clip::sphere(2));
  Mesh m;
  m.positions = {{-0.5, 0, 0.9}, {0.1, 0.8, 0.5}, {0.1, -0.8, 0.5}};
  m.triangles = {{0, 1, 2}};
  const ImproveStats st = improve_mesh(m, s, {.max_steps = 3});
  EXPECT_EQ(st.undefined_vertices, 1);
  EXPECT_EQ(st.max_residual, std::numeric_limits<double>::max());
}

// Improved meshes of fields undefined on part of the clip stay inside the clip and where F is
// finite, and end on F = 0.
TEST(ImproveNonFinite, VerticesStayInsideTheClipWhereFIsFinite) {
  for (const char* eq : {"sqrt(x) + y^2 + z^2 - 1", "log(x + 0.3) + y^2 + z^2", "z - 0.4*x"}) {
    SCOPED_TRACE(eq);
    const Surface s = test::equation(eq, Clip::sphere(1.5));
    Mesh m = polygonize(s, {.cells = 32});
    ASSERT_FALSE(m.positions.empty());
    const ImproveStats st = improve_mesh(m, s, {.max_steps = 60});
    Evaluator ev(s.field);
    for (const Vec3& p : m.positions) {
      ASSERT_TRUE(s.clip.contains(p, 1e-9)) << p.transpose();
      ASSERT_TRUE(std::isfinite(ev.value(p))) << p.transpose();
    }
    EXPECT_EQ(st.undefined_vertices, 0);
    EXPECT_LT(st.max_residual, 1e-6);
  }
}

}  // namespace
}  // namespace zeroset
