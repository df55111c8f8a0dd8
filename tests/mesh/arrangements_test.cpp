// Crossings on surfaces nobody named: random products of quadrics, checked against their
// exactly known double curves (docs/meshing.md, "Crossings: the arrangements sweep"), and a
// join that fails somewhere leaving only that place as marching cubes made it.
#include <gtest/gtest.h>

#include <fmt/core.h>

#include "arrangements.h"
#include "support/equation.h"
#include "zeroset/mesh/mesh_surface.h"

namespace zeroset {
namespace {

using test::Arrangement;
using test::ArrangementCheck;
using test::ArrangementFigures;
using test::Quadric;

MeshResult mesh_at(const Surface& s, int cells) {
  MeshSettings settings;
  settings.cells = cells;
  MeshRun run;
  run.survey = false;
  return mesh_surface(s, settings, run);
}

// y z (x² + y − z + 0.1): the x axis, and two parabolas 0.1 from it at x = 0, in the planes.
// Between the axis and the parabolas, three cells wide at 64 cells (at 96 too), the rim of the cut passes
// from one curve to the other and could not be joined; the whole mesh used to be left as
// marching cubes made it.
TEST(Arrangements, AJoinThatFailsLeavesOnlyItsPlaceAsMarchingCubes) {
  Arrangement a;
  a.factors.push_back({.kind = "plane", .b = Vec3(0, 1, 0)});
  a.factors.push_back({.kind = "plane", .b = Vec3(0, 0, 1)});
  Quadric p{.kind = "paraboloid", .b = Vec3(0, 1, -1), .c = 0.1};
  p.a(0, 0) = 1;
  a.factors.push_back(p);
  const Surface s = test::equation("y*z*(x^2+y-z+0.1)", Clip::sphere(1.047));
  for (const int cells : {64, 96, 128}) {
    SCOPED_TRACE(fmt::format("{} cells", cells));
    const MeshResult r = mesh_at(s, cells);
    ASSERT_TRUE(r.crossings);
    EXPECT_EQ(r.crossings->failure, "");
    EXPECT_EQ(r.crossings->crossing_curves, 3);
    ArrangementCheck check{.radius = 1.047};
    const ArrangementFigures all = test::check_arrangement(r.mesh, a, check);
    // Away from the places left, every crossing is treated.
    for (const CrossingStats::Place& p : r.crossings->left_as_marching_cubes) {
      check.skip_near.push_back(p.at);
      check.skip_radius = std::max(check.skip_radius, p.radius + 3 * 2.094 / cells);
    }
    const ArrangementFigures elsewhere = test::check_arrangement(r.mesh, a, check);
    EXPECT_GT(elsewhere.curve_points, all.curve_points / 4);
    EXPECT_GE(elsewhere.curve_fraction(), 0.99);
    EXPECT_GE(elsewhere.sheet_fraction(), 0.99);
    // The warning names the first place.
    if (!r.crossings->left_as_marching_cubes.empty()) {
      ASSERT_FALSE(r.warnings.empty());
      EXPECT_NE(r.warnings.front().find("left as marching cubes"), std::string::npos);
    }
  }
}

// A smaller sweep than the figures in docs/meshing.md (16 products at 48 cells): no product is
// left untreated as a whole, and the figures do not fall below what was measured (sheets
// 91.2%, curves 82.1%, 5 products passing every check; before the crossings degraded locally
// and the singular set followed narrow crossings, sheets 35% and curves 12% on such sweeps).
TEST(Arrangements, RandomProductsOfQuadricsMeetOnTheirDoubleCurves) {
  test::ArrangementGenerator generator(2026);
  long long sheet_points = 0, sheet_on = 0, curve_points = 0, curve_on = 0;
  int passed = 0;
  constexpr int kProducts = 16;
  for (int k = 0; k < kProducts; ++k) {
    const Arrangement a = generator.next();
    SCOPED_TRACE(fmt::format("product {}: {}", k, a.expression()));
    const MeshResult r = mesh_at(test::equation(a.expression(), Clip::sphere(1)), 48);
    ASSERT_TRUE(r.crossings);
    EXPECT_EQ(r.crossings->failure, "");
    const ArrangementFigures f = test::check_arrangement(r.mesh, a);
    sheet_points += f.sheet_points, sheet_on += f.sheet_on_mesh;
    curve_points += f.curve_points, curve_on += f.curve_on_four;
    passed += f.sheet_fraction() >= 0.99 && f.curve_fraction() >= 1.0 && r.improvement &&
              r.improvement->summary().converged;
  }
  const double sheets = static_cast<double>(sheet_on) / static_cast<double>(sheet_points);
  const double curves = static_cast<double>(curve_on) / static_cast<double>(curve_points);
  RecordProperty("sheets", fmt::format("{:.4f}", sheets));
  RecordProperty("curves", fmt::format("{:.4f}", curves));
  EXPECT_GE(sheets, 0.89);
  EXPECT_GE(curves, 0.79);
  EXPECT_GE(passed, 4);
}

}  // namespace
}  // namespace zeroset
