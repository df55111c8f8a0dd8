#include <gtest/gtest.h>

#include <cmath>

#include "mesh_test_support.h"
#include "zeroset/error.h"
#include "zeroset/mesh/adjacency.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"

namespace zeroset {
namespace {

TEST(Improve, SphereGetsBetterTrianglesAndStaysOnTheSurface) {
  const Surface s = test::catalog_surface("sphere");
  Mesh m = polygonize(s, {.cells = 24});
  const MeshQuality before = measure_quality(m, s);
  const ImproveStats st = improve_mesh(m, s);
  const MeshQuality after = measure_quality(m, s);
  EXPECT_TRUE(st.converged);
  EXPECT_GT(after.mean_min_angle_deg, before.mean_min_angle_deg + 8);
  EXPECT_LT(after.percent_below_30, before.percent_below_30 / 3);
  EXPECT_LT(after.max_residual, 1e-9);
  EXPECT_EQ(after.flipped_triangles, 0u);
  const MeshTopology t = mesh_topology(m);
  EXPECT_TRUE(t.is_watertight());
  EXPECT_EQ(t.euler_characteristic, 2);
}

TEST(Improve, NeverFlipsATriangleOnTheTorus) {
  const Surface s = test::catalog_surface("torus");
  MeshImprover imp(polygonize(s, {.cells = 20}), s, {.max_move_fraction = 1.0});
  for (int k = 0; k < 40; ++k) {
    imp.step();
    EXPECT_EQ(imp.stats().flipped_triangles, 0) << "step " << k;
  }
  imp.finish();
  EXPECT_EQ(measure_quality(imp.mesh(), s).flipped_triangles, 0u);
  EXPECT_EQ(mesh_topology(imp.mesh()).euler_characteristic, 0);
}

TEST(Improve, FixedBoundaryVerticesDoNotMove) {
  const Surface s = test::kummer(1.5, 3);
  Mesh m = polygonize(s, {.cells = 24});
  const Mesh before = m;
  improve_mesh(m, s, {.max_steps = 30, .boundary = BoundaryMode::kFixed});
  ASSERT_EQ(m.positions.size(), before.positions.size());
  size_t boundary = 0;
  for (size_t v = 0; v < m.positions.size(); ++v)
    if (before.is_boundary[v]) {
      ++boundary;
      EXPECT_EQ(m.positions[v], before.positions[v]);
    }
  EXPECT_GT(boundary, 0u);
}

TEST(Improve, ConstrainedBoundaryVerticesSlideAlongTheClipCurve) {
  const Surface s = test::kummer(1.5, 3);
  Mesh m = polygonize(s, {.cells = 24});
  const Mesh before = m;
  improve_mesh(m, s, {.max_steps = 60, .boundary = BoundaryMode::kConstrained});
  Evaluator ev(s.field);
  double moved = 0;
  for (size_t v = 0; v < m.positions.size(); ++v) {
    if (!m.is_boundary[v]) continue;
    EXPECT_LE(std::abs(s.clip.value(m.positions[v])), 1e-9);
    Vec3 g;
    const double f = ev.value_gradient(m.positions[v], g);
    EXPECT_LT(std::abs(f) / g.norm(), 1e-7);
    moved = std::max(moved, (m.positions[v] - before.positions[v]).norm());
  }
  EXPECT_GT(moved, 1e-3);
}

TEST(Improve, FindsTheKummerNodesFromTheFieldAlone) {
  Surface s = test::kummer(1.5, 3);
  s.singular_points_fn = nullptr;  // the improver must not need them
  Mesh m = polygonize(s, {.cells = 32});
  const ImproveStats st = improve_mesh(m, s, {.max_steps = 30});
  const auto known = test::kummer(1.5, 3).singular_points();
  ASSERT_EQ(known.size(), 16u);
  EXPECT_EQ(st.singular_points.size(), 16u);
  for (const Vec3& q : known) {
    double nearest = 1e9;
    for (const Vec3& p : m.positions) nearest = std::min(nearest, (p - q).norm());
    EXPECT_LT(nearest, 1e-9);
  }
}

TEST(Improve, NoMoveLeavesTheSurfaceOnTheKummerSurface) {
  const Surface s = test::kummer(1.5, 3);
  Mesh m = polygonize(s, {.cells = 32});
  improve_mesh(m, s);
  const MeshQuality q = measure_quality(m, s);
  EXPECT_LT(q.max_residual, 1e-6);
  EXPECT_EQ(q.flipped_triangles, 0u);
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.misoriented_edges, 0u);
}

TEST(Improve, SteppingMatchesTheOneCallVersion) {
  const Surface s = test::catalog_surface("torus");
  const Mesh start = polygonize(s, {.cells = 16});
  Mesh a = start;
  improve_mesh(a, s, {.max_steps = 12});
  MeshImprover imp(start, s, {.max_steps = 12});
  for (int k = 0; k < 12 && !imp.converged(); ++k) imp.step();
  imp.finish();
  EXPECT_EQ(imp.mesh().positions, a.positions);
  EXPECT_EQ(imp.mesh().triangles, a.triangles);
}

TEST(Improve, EverySwitchCanBeTurnedOff) {
  const Surface s = test::kummer(1.5, 3);
  Mesh m = polygonize(s, {.cells = 20});
  const size_t triangles = m.triangle_count();
  const ImproveStats st = improve_mesh(m, s,
                                       {.max_steps = 10,
                                        .inertia = 0,
                                        .use_curvature = false,
                                        .use_singularity = false,
                                        .find_singular_points = false,
                                        .flip_edges = false});
  EXPECT_EQ(st.flips, 0);
  EXPECT_TRUE(st.singular_points.empty());
  EXPECT_EQ(m.triangle_count(), triangles);
}

TEST(Improve, RejectsBadOptions) {
  const Surface s = test::catalog_surface("sphere");
  const Mesh m = polygonize(s, {.cells = 8});
  EXPECT_THROW(MeshImprover(m, s, {.relaxation = 0}), InvalidArgument);
  EXPECT_THROW(MeshImprover(m, s, {.inertia = 1}), InvalidArgument);
  EXPECT_THROW(MeshImprover(m, s, {.speed_threshold = -1}), InvalidArgument);
  Mesh broken = m;
  broken.triangles.push_back({0, 1, 999999});
  EXPECT_THROW(MeshImprover(broken, s), InvalidArgument);
}

}  // namespace
}  // namespace zeroset
