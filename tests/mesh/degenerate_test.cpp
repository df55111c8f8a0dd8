// No degenerate output: no triangle of zero area and no two vertices at one point, on surfaces
// where F vanishes exactly at many grid nodes (integer coefficients on grids of rational
// spacing) and on every catalog surface, at 16 to 128 cells.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "mesh/mesh_test_support.h"
#include "zeroset/mesh/crossings.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"
#include "zeroset/surface/catalog.h"

namespace zeroset {
namespace {

const int kResolutions[] = {16, 32, 64, 128};

struct Case {
  std::string name;
  Surface surface;
};

// Each has whole lines or planes of exact zeros through grid nodes, or points (the cone's
// Pythagorean triples) where F vanishes exactly.
std::vector<Case> exact_zero_surfaces() {
  std::vector<Case> out;
  out.push_back({"cone", test::equation("x^2 + y^2 - z^2", Clip::sphere(1.5))});
  out.push_back({"cone 2", test::equation("x^2 + y^2 - 2*z^2", Clip::sphere(2))});
  out.push_back({"sphere 5", test::equation("x^2 + y^2 + z^2 - 25", Clip::sphere(6))});
  out.push_back({"cylinder", test::equation("x^2 + y^2 - 1", Clip::sphere(2))});
  out.push_back({"xy", test::equation("x*y", Clip::sphere(2))});
  out.push_back({"xyz", test::equation("x*y*z", Clip::sphere(2))});
  out.push_back({"x2-y2", test::equation("x^2 - y^2", Clip::sphere(2))});
  out.push_back({"whitney", test::equation("x^2 - y^2*z", Clip::sphere(2))});
  out.push_back({"cayley", test::catalog_surface("cayley")});
  out.push_back({"planes", test::catalog_surface("planes")});
  for (double mu : {1.0, 2.0, 3.0})
    out.push_back({"kummer " + std::to_string(mu), test::kummer(mu)});
  return out;
}

void expect_no_degenerate(const Mesh& mesh, const Surface& surface, const std::string& what) {
  ASSERT_FALSE(mesh.empty()) << what;
  const MeshQuality q = measure_quality(mesh, surface);
  EXPECT_EQ(q.zero_area_triangles, 0u) << what;
  EXPECT_EQ(q.coincident_vertices, 0u) << what;
  for (const auto& t : mesh.triangles)
    ASSERT_TRUE(t[0] != t[1] && t[1] != t[2] && t[2] != t[0]) << what;
}

Mesh polygonized(const Surface& surface, int cells, PolygonizeStats* st = nullptr) {
  PolygonizeOptions po;
  po.cells = cells;
  return polygonize(surface, po, st);
}

class ExactZeros : public testing::TestWithParam<size_t> {};

TEST_P(ExactZeros, OneVertexPerPointAndNoFlatTriangles) {
  const Case c = exact_zero_surfaces()[GetParam()];
  for (int cells : kResolutions) {
    PolygonizeStats st;
    Mesh mesh = polygonized(c.surface, cells, &st);
    const std::string what = c.name + " at " + std::to_string(cells) + " cells";
    expect_no_degenerate(mesh, c.surface, what + " (marching cubes)");
    mesh_crossings(mesh, c.surface, st.cell_size);
    expect_no_degenerate(mesh, c.surface, what + " (with crossings)");
  }
}

INSTANTIATE_TEST_SUITE_P(Degenerate, ExactZeros,
                         testing::Range<size_t>(0, exact_zero_surfaces().size()));

TEST(Degenerate, TheConeWeldsItsGridZeros) {
  // The case the welding is for: at 128 cells over the sphere of radius 1.5 the cone meets
  // hundreds of nodes exactly, and each used to give several vertices at one point.
  PolygonizeStats st;
  const Surface cone = test::equation("x^2 + y^2 - z^2", Clip::sphere(1.5));
  const Mesh mesh = polygonized(cone, 128, &st);
  EXPECT_GT(st.welded_vertices, 100);
  expect_no_degenerate(mesh, cone, "cone");
}

// The whole pipeline of `zeroset mesh` on every catalog surface. At 128 cells the improver
// runs 30 steps (moves and flips, not the approach to rest), which keeps this test short.
class CatalogMeshes : public testing::TestWithParam<size_t> {};

TEST_P(CatalogMeshes, NoFlatTriangleAfterCrossingsAndImprovement) {
  const CatalogEntry& entry = catalog()[GetParam()];
  for (int cells : kResolutions) {
    const Surface surface = make_surface(entry);
    PolygonizeStats st;
    Mesh mesh = polygonized(surface, cells, &st);
    mesh_crossings(mesh, surface, st.cell_size);
    ImproveOptions io;
    if (cells == 128) io.max_steps = 30;
    improve_mesh(mesh, surface, io);
    expect_no_degenerate(mesh, surface, entry.name + " at " + std::to_string(cells) + " cells");
  }
}

INSTANTIATE_TEST_SUITE_P(Degenerate, CatalogMeshes, testing::Range<size_t>(0, catalog().size()));

}  // namespace
}  // namespace zeroset
