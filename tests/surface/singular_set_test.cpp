// The singular set found on surfaces whose singular points and curves are known exactly.
#include "zeroset/surface/singular_set.h"

#include <gtest/gtest.h>

#include <cmath>

#include "support/equation.h"
#include "zeroset/error.h"
#include "zeroset/io/memory.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset {
namespace {

Surface equation(const std::string& text, const std::string& clip) {
  return resolve_surface(text, {.params = {}, .clip_specs = {clip}});
}

// Every vertex of every curve satisfies F = 0 and ∇F = 0 to 1e-12 of the scene radius
// (|F|/|H| and |∇F|/|H| as distances).
void expect_on_singular_set(const Surface& s, const SingularSet& set) {
  Evaluator ev(s.field);
  const double r = s.scene_radius();
  for (const SingularCurve& c : set.curves)
    for (const Vec3& p : c.points) {
      const FieldSample fs = ev.sample(p, Derivatives::kHessian);
      const double h = std::max(fs.hessian.norm(), 1e-300);
      EXPECT_LE(fs.gradient.norm() / h, 1e-12 * r) << p.transpose();
    }
}

using test::catalog_surface;

int points_of(const SingularSet& set, SingularPointKind kind) {
  return static_cast<int>(set.points_of(kind).size());
}

TEST(SingularSet, AGridBeyondTheMemoryIsRefusedNamingWhatFits) {
  // 1025³ nodes of F, ∇F and the Hessian: about 112 GB.
  const MemoryLimit have = available_memory();
  if (!have.known || have.budget() > 1.2e11) GTEST_SKIP() << "this machine would hold the grid";
  try {
    find_singular_set(test::catalog_surface("sphere"), {.cells = 1024});
    FAIL() << "a grid of 112 GB was searched";
  } catch (const InvalidArgument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("1024"), std::string::npos) << what;
    EXPECT_NE(what.find("cells or fewer"), std::string::npos) << what;
  }
}

TEST(SingularSet, RomanHasThreeCrossingSegmentsATriplePointAndSixPinches) {
  const Surface s = catalog_surface("roman");
  const SingularSet set = find_singular_set(s);
  EXPECT_EQ(set.count(CurveKind::kCrossing), 3);
  EXPECT_EQ(set.count(CurveKind::kIsolated), 6);
  EXPECT_EQ(points_of(set, SingularPointKind::kTriple), 1);
  ASSERT_EQ(points_of(set, SingularPointKind::kPinch), 6);
  for (const Vec3& p : set.points_of(SingularPointKind::kPinch)) {
    EXPECT_NEAR(p.norm(), 0.5, 1e-12);
    EXPECT_NEAR(p.cwiseAbs().maxCoeff(), 0.5, 1e-12);  // on an axis
  }
  EXPECT_LT(set.points_of(SingularPointKind::kTriple)[0].norm(), 1e-9);
  for (const SingularCurve& c : set.curves) {
    if (c.kind == CurveKind::kCrossing) {
      EXPECT_NEAR(c.length(), 1.0, 1e-6);
    }
    if (c.kind == CurveKind::kIsolated) {
      EXPECT_NEAR(c.length(), 0.1, 1e-6);
    }
  }
  expect_on_singular_set(s, set);
}

TEST(SingularSet, WhitneyHasAPinchACrossingHalfLineAndAnIsolatedHandle) {
  const Surface s = catalog_surface("whitney");
  const SingularSet set = find_singular_set(s);
  ASSERT_EQ(set.curves.size(), 2u);
  ASSERT_EQ(points_of(set, SingularPointKind::kPinch), 1);
  EXPECT_LT(set.points_of(SingularPointKind::kPinch)[0].norm(), 1e-12);
  for (const SingularCurve& c : set.curves) {
    const double z = 0.5 * (c.points.front().z() + c.points.back().z());
    EXPECT_EQ(c.kind, z > 0 ? CurveKind::kCrossing : CurveKind::kIsolated);
    EXPECT_NEAR(c.length(), 1.0, 1e-6);
    for (const Vec3& p : c.points) EXPECT_LT(p.head<2>().norm(), 1e-12);
  }
  EXPECT_EQ(points_of(set, SingularPointKind::kClipEnd), 2);
}

TEST(SingularSet, KummerAtMuThreeIsSixLinesWithFourTriplePoints) {
  Surface s = catalog_surface("kummer");
  s.field.set_parameter("mu", 3.0);
  const SingularSet set = find_singular_set(s);
  EXPECT_EQ(set.count(CurveKind::kCrossing), 6);
  EXPECT_EQ(set.curves.size(), 6u);
  EXPECT_EQ(points_of(set, SingularPointKind::kTriple), 4);
  EXPECT_EQ(points_of(set, SingularPointKind::kNode), 0);
  expect_on_singular_set(s, set);
}

TEST(SingularSet, KummerAtMuOneAndAHalfHasSixteenNodes) {
  Surface s = catalog_surface("kummer");
  s.field.set_parameter("mu", 1.5);
  const SingularSet set = find_singular_set(s);
  EXPECT_TRUE(set.curves.empty());
  EXPECT_EQ(points_of(set, SingularPointKind::kNode), 16);
}

TEST(SingularSet, PlanesHaveOneLine) {
  Surface s = catalog_surface("planes");
  s.field.set_parameter("a", 0.3);
  const SingularSet set = find_singular_set(s);
  ASSERT_EQ(set.curves.size(), 1u);
  EXPECT_EQ(set.curves[0].kind, CurveKind::kCrossing);
  for (const Vec3& p : set.curves[0].points) {
    EXPECT_NEAR(p.x(), 0.3, 1e-12);
    EXPECT_NEAR(p.y(), -0.3, 1e-12);
  }
  EXPECT_NEAR(set.curves[0].length(), 2 * std::sqrt(1 - 2 * 0.09), 1e-9);
}

TEST(SingularSet, SphereCrossingACylinderGivesTwoClosedCircles) {
  const Surface s = equation("(x^2 + y^2 + z^2 - 1)*(x^2 + y^2 - 0.25)", "sphere:1.5");
  const SingularSet set = find_singular_set(s);
  ASSERT_EQ(set.curves.size(), 2u);
  for (const SingularCurve& c : set.curves) {
    EXPECT_TRUE(c.closed);
    EXPECT_EQ(c.kind, CurveKind::kCrossing);
    EXPECT_NEAR(std::abs(c.points[0].z()), std::sqrt(0.75), 1e-12);
    for (const Vec3& p : c.points) EXPECT_NEAR(p.head<2>().norm(), 0.5, 1e-12);
  }
  EXPECT_TRUE(set.points.empty());
  expect_on_singular_set(s, set);
}

TEST(SingularSet, TwoSpheresMeetInACircleAndACuspidalEdgeIsDegenerate) {
  const SingularSet spheres =
      find_singular_set(equation("(x^2 + y^2 + z^2 - 1)*((x - 1)^2 + y^2 + z^2 - 1)", "sphere:2"));
  ASSERT_EQ(spheres.curves.size(), 1u);
  EXPECT_TRUE(spheres.curves[0].closed);
  EXPECT_EQ(spheres.curves[0].kind, CurveKind::kCrossing);
  EXPECT_NEAR(spheres.curves[0].length(), 2 * M_PI * std::sqrt(0.75), 2e-3);
  for (const Vec3& p : spheres.curves[0].points) EXPECT_NEAR(p.x(), 0.5, 1e-12);

  const SingularSet cusp = find_singular_set(equation("x^2 - y^3", "sphere:1"));
  ASSERT_EQ(cusp.curves.size(), 1u);
  EXPECT_EQ(cusp.curves[0].kind, CurveKind::kDegenerate);
  EXPECT_NEAR(cusp.curves[0].length(), 2.0, 1e-9);
}

TEST(SingularSet, ConeHasOneNodeAndSmoothSurfacesNone) {
  EXPECT_EQ(points_of(find_singular_set(catalog_surface("cone")), SingularPointKind::kNode), 1);
  EXPECT_TRUE(find_singular_set(catalog_surface("sphere")).empty());
  EXPECT_TRUE(find_singular_set(catalog_surface("torus")).empty());
}

TEST(SingularSet, FindsTheClassicalNodes) {
  for (auto [name, nodes] :
       {std::pair<const char*, int>{"cayley", 4}, {"barth6", 50}, {"dingdong", 1}}) {
    const SingularSet set = find_singular_set(catalog_surface(name));
    EXPECT_EQ(points_of(set, SingularPointKind::kNode), nodes) << name;
    EXPECT_TRUE(set.curves.empty()) << name;
  }
  for (double mu : {1.02, 2.44}) {
    Surface s = catalog_surface("kummer");
    s.field.set_parameter("mu", mu);
    EXPECT_EQ(points_of(find_singular_set(s), SingularPointKind::kNode), 16) << mu;
  }
}

TEST(SingularSet, KummerAtOneThirdIsADoubleSphere) {
  Surface s = catalog_surface("kummer");
  s.field.set_parameter("mu", 1.0 / 3);
  const SingularSet set = find_singular_set(s);
  EXPECT_TRUE(set.has_singular_sheet);
  EXPECT_NEAR(set.singular_sheet_example.norm(), std::sqrt(1.0 / 3), 1e-6);
}

TEST(SingularSet, ABoxClipCutsTheCurvesAtItsFaces) {
  Surface s = catalog_surface("whitney");
  s.clip = Clip::box(Box3::cube(0.7));
  const SingularSet set = find_singular_set(s);
  ASSERT_EQ(set.curves.size(), 2u);
  for (const SingularCurve& c : set.curves) EXPECT_NEAR(c.length(), 0.7, 1e-9);
}

TEST(SingularSet, ASquareIsReportedAsASingularSheet) {
  const SingularSet set = find_singular_set(equation("(x^2 + y^2 + z^2 - 1)^2", "sphere:1.5"));
  EXPECT_TRUE(set.has_singular_sheet);
  EXPECT_NEAR(set.singular_sheet_example.norm(), 1.0, 1e-6);
  EXPECT_TRUE(set.curves.empty());
}

}  // namespace
}  // namespace zeroset
