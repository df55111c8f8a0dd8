#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stop_token>

#include <Eigen/Geometry>

#include "mesh_test_support.h"
#include "zeroset/error.h"
#include "zeroset/mesh/adjacency.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"

namespace zeroset {
namespace {

double max_residual(const Surface& s, const Mesh& m) {
  Evaluator ev(s.field);
  double worst = 0;
  for (const Vec3& p : m.positions) {
    Vec3 g;
    const double f = ev.value_gradient(p, g);
    worst = std::max(worst, std::abs(f) / g.norm());
  }
  return worst;
}

// Triangles whose normal points against ∇F at the centroid.
size_t faces_against_gradient(const Surface& s, const Mesh& m) {
  Evaluator ev(s.field);
  size_t n = 0;
  for (const auto& t : m.triangles) {
    const Vec3 &a = m.positions[t[0]], &b = m.positions[t[1]], &c = m.positions[t[2]];
    Vec3 g;
    ev.value_gradient((a + b + c) / 3, g);
    n += (b - a).cross(c - a).dot(g) < 0;
  }
  return n;
}

// Triangles in a canonical order (the paths emit them in different orders).
std::vector<std::array<std::uint32_t, 3>> sorted(std::vector<std::array<std::uint32_t, 3>> t) {
  for (auto& tri : t) std::rotate(tri.begin(), std::min_element(tri.begin(), tri.end()), tri.end());
  std::sort(t.begin(), t.end());
  return t;
}

TEST(Polygonize, SphereIsWatertightWithEulerCharacteristicTwo) {
  const Surface s = test::catalog_surface("sphere");
  for (int cells : {5, 16, 41}) {
    const Mesh m = polygonize(s, {.cells = cells});
    const MeshTopology t = mesh_topology(m);
    EXPECT_TRUE(t.is_watertight()) << cells;
    EXPECT_EQ(t.euler_characteristic, 2) << cells;
    EXPECT_EQ(m.is_boundary.size(), m.positions.size());
    for (auto b : m.is_boundary) EXPECT_EQ(b, 0);
  }
}

TEST(Polygonize, TorusIsWatertightWithEulerCharacteristicZero) {
  const Surface s = test::catalog_surface("torus");
  const Mesh m = polygonize(s, {.cells = 48});
  const MeshTopology t = mesh_topology(m);
  EXPECT_TRUE(t.is_watertight());
  EXPECT_EQ(t.euler_characteristic, 0);
}

TEST(Polygonize, BoundedKummerIsClosedInsideItsClip) {
  // mu = 0.5 lies between the double sphere and the Roman surface: a closed quartic.
  const Surface s = test::kummer(0.5, 3);
  const Mesh m = polygonize(s, {.cells = 40});
  ASSERT_FALSE(m.empty());
  for (const Vec3& p : m.positions) EXPECT_LT(p.norm(), 2.5);  // well inside the clip
  EXPECT_TRUE(mesh_topology(m).is_watertight());
}

TEST(Polygonize, VerticesLieOnTheSurfaceAndFacesFollowTheGradient) {
  const Surface s = test::catalog_surface("torus");
  const Mesh m = polygonize(s, {.cells = 32});
  EXPECT_LT(max_residual(s, m), 1e-10);
  EXPECT_EQ(faces_against_gradient(s, m), 0u);
  ASSERT_EQ(m.normals.size(), m.positions.size());
  for (const Vec3& n : m.normals) EXPECT_NEAR(n.norm(), 1, 1e-12);
}

TEST(Polygonize, VerticesConvergeWhereTheSurfaceTouchesAGridLine) {
  // The torus's top circle (z = r) lies in a grid plane at these resolutions: the x edges
  // through it touch the surface (F has a double root there), where Newton's method alone
  // crawls and stops far from the root after its few steps.
  const Surface s = test::catalog_surface("torus");
  for (int cells : {32, 40}) {
    PolygonizeStats st;
    const Mesh m = polygonize(s, {.cells = cells}, &st);
    EXPECT_LT(max_residual(s, m), 1e-12 * st.cell_size) << cells;
  }
}

TEST(Polygonize, BoundaryVerticesLieOnTheClipAndTheSurface) {
  const Surface s = test::kummer(1.5, 3);
  PolygonizeStats st;
  const Mesh m = polygonize(s, {.cells = 48}, &st);
  const MeshTopology t = mesh_topology(m);
  EXPECT_GT(t.boundary_edges, 0u);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.misoriented_edges, 0u);
  Evaluator ev(s.field);
  size_t flagged = 0;
  for (size_t v = 0; v < m.positions.size(); ++v) {
    if (!m.is_boundary[v]) continue;
    ++flagged;
    EXPECT_LE(std::abs(s.clip.value(m.positions[v])), 1e-9);
    Vec3 g;
    const double f = ev.value_gradient(m.positions[v], g);
    EXPECT_LT(std::abs(f) / g.norm(), 1e-8);
  }
  EXPECT_GT(flagged, 0u);
  for (const Vec3& p : m.positions) EXPECT_LE(s.clip.value(p), 1e-9);
  // Every boundary edge joins two flagged vertices.
  const MeshAdjacency adj = build_adjacency(m);
  for (size_t e = 0; e < adj.edges.size(); ++e)
    if (adj.edge_triangle_count[e] == 1) {
      EXPECT_TRUE(m.is_boundary[adj.edges[e][0]]);
      EXPECT_TRUE(m.is_boundary[adj.edges[e][1]]);
    }
}

TEST(Polygonize, BoxClipCutsAlongItsPlanes) {
  const Surface s = test::equation("x^2 + y^2 - z^2 - 0.1", Clip::box(Box3::cube(1)));
  const Mesh m = polygonize(s, {.cells = 30});
  ASSERT_FALSE(m.empty());
  for (size_t v = 0; v < m.positions.size(); ++v) {
    if (m.is_boundary[v]) {
      EXPECT_LE(std::abs(s.clip.value(m.positions[v])), 1e-9);
    }
  }
  EXPECT_EQ(mesh_topology(m).non_manifold_edges, 0u);
}

TEST(Polygonize, BoxClipLeavesNoSliversInItsPlanes) {
  // Grid faces lie in a box clip's planes: triangles there whose three vertices are all on the
  // clip are slivers between boundary vertices, often facing against ∇F, and are dropped.
  for (double half : {2.5, 3.0}) {
    Surface k = test::kummer(1.5);
    k.clip = Clip::box(Box3::cube(half));
    const Mesh m = polygonize(k, {.cells = 64});
    const MeshQuality q = measure_quality(m, k);
    EXPECT_EQ(q.flipped_triangles, 0u) << half;
    EXPECT_GT(q.smallest_angle_deg, 0.0) << half;
    EXPECT_EQ(mesh_topology(m).non_manifold_edges, 0u) << half;
  }
  // Where the surface lies in the clip's plane, its triangles stay: z = 1 on the box's top.
  const Surface top = test::equation("z - 1", Clip::box(Box3::cube(1)));
  const Mesh m = polygonize(top, {.cells = 20});
  EXPECT_EQ(m.triangle_count(), 800u);
}

TEST(Polygonize, AmbiguousFacesGiveAConsistentManifold) {
  // A wavy field with many saddles on cube faces at this resolution.
  const Surface s = test::equation("sin(7*x)*sin(7*y)*sin(7*z) + 0.02*x", Clip::sphere(1));
  PolygonizeStats st;
  const Mesh m = polygonize(s, {.cells = 17}, &st);
  EXPECT_GT(st.ambiguous_faces, 0);
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.non_manifold_edges, 0u);
  EXPECT_EQ(t.misoriented_edges, 0u);
  EXPECT_EQ(t.degenerate_triangles, 0u);
}

TEST(Polygonize, SparseGridMatchesDenseGrid) {
  const Surface s = test::kummer(1.5, 3);
  PolygonizeStats sd, ss;
  const Mesh dense = polygonize(s, {.cells = 40, .mode = GridMode::kDense}, &sd);
  const Mesh sparse =
      polygonize(s, {.cells = 40, .mode = GridMode::kSparse, .brick_cells = 4}, &ss);
  EXPECT_TRUE(ss.sparse);
  EXPECT_EQ(sorted(sparse.triangles), sorted(dense.triangles));
  EXPECT_EQ(sparse.positions, dense.positions);
}

TEST(Polygonize, DenseSlabsMatchSparseBricksOnAnUnevenGrid) {
  // 45 cell layers: the dense path's last slab is shorter than the others, and no axis has
  // the same number of cells.
  const Surface s = test::kummer(1.5, 3);
  const Box3 box{Vec3(-3, -2.1, -2.7), Vec3(2.4, 2.7, 3)};
  const PolygonizeOptions base{.bounds = box, .cells = 45};
  PolygonizeOptions dense_options = base, sparse_options = base;
  dense_options.mode = GridMode::kDense;
  sparse_options.mode = GridMode::kSparse;
  sparse_options.brick_cells = 4;
  PolygonizeStats sd;
  const Mesh dense = polygonize(s, dense_options, &sd);
  const Mesh sparse = polygonize(s, sparse_options);
  EXPECT_NE(sd.cells[0], sd.cells[1]);
  EXPECT_NE(sd.cells[1], sd.cells[2]);
  ASSERT_FALSE(dense.empty());
  EXPECT_EQ(sorted(sparse.triangles), sorted(dense.triangles));
  EXPECT_EQ(sparse.positions, dense.positions);
}

TEST(Polygonize, SparseGridSkipsEmptySpace) {
  const Surface s = test::catalog_surface("torus");
  PolygonizeStats ss;
  const Mesh sparse =
      polygonize(s, {.cells = 96, .mode = GridMode::kSparse, .brick_cells = 4}, &ss);
  const Mesh dense = polygonize(s, {.cells = 96, .mode = GridMode::kDense});
  EXPECT_LT(ss.bricks_kept, ss.bricks / 2);
  EXPECT_EQ(sorted(sparse.triangles), sorted(dense.triangles));
}

TEST(Polygonize, ExpressionAndPolynomialSamplingAgree) {
  const Surface s = test::kummer(1.5, 3);
  const Mesh a = polygonize(s, {.cells = 24, .polynomial_rows = true});
  const Mesh b = polygonize(s, {.cells = 24, .polynomial_rows = false});
  EXPECT_EQ(a.triangle_count(), b.triangle_count());
}

TEST(Polygonize, PolynomialTooHighToExpandIsSampledThroughTheExpression) {
  // Degree 26, just above the expansion limit: the unit sphere, watertight, vertices on it.
  const Surface s = test::equation("(x^2 + y^2 + z^2)^13 - 1", Clip::sphere(2));
  ASSERT_FALSE(s.field.is_expandable());
  const Mesh m = polygonize(s, {.cells = 24, .polynomial_rows = true});
  const MeshTopology t = mesh_topology(m);
  EXPECT_TRUE(t.is_watertight());
  EXPECT_EQ(t.euler_characteristic, 2);
  for (const Vec3& p : m.positions) EXPECT_NEAR(p.norm(), 1.0, 1e-6);
}

TEST(Polygonize, ResultDoesNotDependOnThreadCount) {
  const Surface s = test::catalog_surface("torus");
  const Mesh a = polygonize(s, {.cells = 30, .threads = 1});
  const Mesh b = polygonize(s, {.cells = 30, .threads = 2});
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.positions, b.positions);
}

TEST(Polygonize, ReturnsEmptyWhenStopped) {
  std::stop_source src;
  src.request_stop();
  EXPECT_TRUE(
      polygonize(test::catalog_surface("sphere"), {.cells = 30}, nullptr, src.get_token()).empty());
}

TEST(Polygonize, RejectsBadOptions) {
  const Surface s = test::catalog_surface("sphere");
  EXPECT_THROW(polygonize(s, {.cells = 0}), InvalidArgument);
  EXPECT_THROW(polygonize(s, {.cells = 100000}), InvalidArgument);
  EXPECT_THROW(polygonize(s, {.cells = 8, .refine_steps = -1}), InvalidArgument);
  Surface unbounded = test::equation("x + y", Clip{});
  EXPECT_THROW(polygonize(unbounded, {.cells = 8}), BadInput);
}

TEST(Polygonize, PlanEstimatesGrowWithResolution) {
  const Surface s = test::kummer(1.5, 3);
  const GridPlan small = plan_grid(s, {.cells = 64});
  const GridPlan big = plan_grid(s, {.cells = 4096});
  EXPECT_FALSE(small.sparse);
  EXPECT_TRUE(big.sparse);
  EXPECT_EQ(small.cells[0], 64);
  EXPECT_NEAR(small.cell_size, 6.0 / 64, 1e-15);
  EXPECT_GT(big.estimated_bytes, 100 * small.estimated_bytes);
}

}  // namespace
}  // namespace zeroset
