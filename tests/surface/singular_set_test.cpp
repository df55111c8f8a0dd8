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

// Cuspidal edges: F ≈ u² − v³ across the curve, so Q has rank one all along it and det Q
// vanishes identically; its measured sign is rounding (the corrector fixes v only to about 1e-8).
// Each edge must come out as one degenerate curve with no pinch point on it.

// The largest distance from the vertices of the curves of `kind` to a curve given by `distance`.
template <typename Distance>
double farthest(const SingularSet& set, CurveKind kind, Distance distance) {
  double far = 0;
  for (const SingularCurve& c : set.curves)
    if (c.kind == kind)
      for (const Vec3& p : c.points) far = std::max(far, distance(p));
  return far;
}

TEST(SingularSet, ACuspidalCylinderIsOneDegenerateCurveAlongItsEdge) {
  const SingularSet upright = find_singular_set(equation("x^2 - y^3", "box:1"));
  ASSERT_EQ(upright.curves.size(), 1u);
  EXPECT_EQ(upright.curves[0].kind, CurveKind::kDegenerate);
  EXPECT_NEAR(upright.curves[0].length(), 2.0, 1e-9);
  EXPECT_LT(
      farthest(upright, CurveKind::kDegenerate, [](const Vec3& p) { return p.head<2>().norm(); }),
      1e-9);
  EXPECT_EQ(points_of(upright, SingularPointKind::kPinch), 0);

  // The same cylinder about the diagonal: before Q's rank was judged relative to the rounding
  // that v's position carries, this edge came out as 48 pieces and 47 pinch points.
  const Surface s = equation("((x - y)/sqrt(2))^2 - ((x + y - 2*z)/sqrt(6))^3", "box:1");
  const SingularSet tilted = find_singular_set(s);
  ASSERT_EQ(tilted.curves.size(), 1u);
  EXPECT_EQ(tilted.curves[0].kind, CurveKind::kDegenerate);
  EXPECT_NEAR(tilted.curves[0].length(), 2 * std::sqrt(3.0), 1e-9);
  const Vec3 axis = Vec3(1, 1, 1).normalized();
  EXPECT_LT(farthest(tilted, CurveKind::kDegenerate,
                     [&](const Vec3& p) { return (p - p.dot(axis) * axis).norm(); }),
            1e-7);
  EXPECT_TRUE(tilted.points_of(SingularPointKind::kPinch).empty());
  EXPECT_EQ(points_of(tilted, SingularPointKind::kClipEnd), 2);
  expect_on_singular_set(s, tilted);
}

TEST(SingularSet, ACuspidalEdgeAroundACylinderIsOneClosedDegenerateCurve) {
  // (xy − z³ − 1)² = (1 − x² − y²)³: A² − B³, singular where A = B = 0, i.e. on the closed
  // curve (cos θ, sin θ, ∛(sin θ cos θ − 1)), a cuspidal edge all round (∇A and ∇B stay
  // independent there). The surface lies within x² + y² ≤ 1, |z| ≤ ∛2.5, inside the ball of 2.
  // Besides, the origin is an isolated singular point (F ≈ 3x² − 2xy + 3y² + 2z³ there).
  const Surface s = equation("(x*y - z^3 - 1)^2 - (1 - x^2 - y^2)^3", "sphere:2");
  const SingularSet set = find_singular_set(s);
  ASSERT_EQ(set.curves.size(), 1u);
  const SingularCurve& edge = set.curves[0];
  EXPECT_EQ(edge.kind, CurveKind::kDegenerate);
  EXPECT_TRUE(edge.closed);
  EXPECT_NEAR(edge.length(), 6.47345, 2e-3);  // the inscribed polygon, 0.01% short
  EXPECT_LT(farthest(set, CurveKind::kDegenerate,
                     [](const Vec3& p) {
                       return std::abs(p.x() * p.y() - std::pow(p.z(), 3) - 1) +
                              std::abs(1 - p.head<2>().squaredNorm());
                     }),
            1e-7);
  EXPECT_TRUE(set.points_of(SingularPointKind::kPinch).empty());
  ASSERT_EQ(set.points.size(), 1u);
  EXPECT_EQ(set.points[0].kind, SingularPointKind::kDegenerate);
  EXPECT_LT(set.points[0].position.norm(), 1e-7);
  expect_on_singular_set(s, set);
}

TEST(SingularSet, TheSwallowtailHasTwoCuspidalEdgesAndADoubleCurve) {
  // The discriminant of t⁴ + x t² + y t + z. A triple root t = a gives the cuspidal edge
  // (−6a², 8a³, −3a⁴), two double roots ±a the double curve (−2a², 0, a⁴) where two real sheets
  // cross, two complex double roots ±ia the isolated curve (2a², 0, a⁴); they meet at the
  // swallowtail point, the origin, where F vanishes to weighted order 12 and the tolerances
  // cannot tell S from its neighbourhood within about a grid cell (docs/singular.md, Limits).
  const Surface s =
      equation("256*z^3 - 128*x^2*z^2 + 144*x*y^2*z - 27*y^4 + 16*x^4*z - 4*x^3*y^2", "box:1");
  const SingularSet set = find_singular_set(s);
  constexpr double kNearOrigin = 0.1;  // 2.4 grid cells (2/48)
  ASSERT_EQ(set.count(CurveKind::kDegenerate), 2);
  for (const SingularCurve& c : set.curves) {
    if (c.kind != CurveKind::kDegenerate) continue;
    // From the clip (x = −1, a = ±1/√6) to the origin, along one branch a > 0 or a < 0.
    const Vec3 far_end =
        c.points.front().x() < c.points.back().x() ? c.points.front() : c.points.back();
    const Vec3 near_end =
        c.points.front().x() < c.points.back().x() ? c.points.back() : c.points.front();
    EXPECT_NEAR(far_end.x(), -1, 1e-7);  // as far as the edge is known across it
    EXPECT_NEAR(std::abs(far_end.y()), 8 * std::pow(1 / std::sqrt(6.0), 3), 1e-7);
    EXPECT_LT(near_end.norm(), kNearOrigin);
    for (const Vec3& p : c.points) {
      const double a = std::cbrt(p.y() / 8);
      EXPECT_NEAR(p.x(), -6 * a * a, 1e-7) << p.transpose();
      EXPECT_NEAR(p.z(), -3 * std::pow(a, 4), 1e-7) << p.transpose();
    }
  }
  for (const Vec3& p : set.points_of(SingularPointKind::kPinch))
    EXPECT_LT(p.norm(), kNearOrigin)
        << "a pinch point away from the swallowtail point: " << p.transpose();
  // The double curve is still a crossing curve, the isolated branch still isolated, each from
  // the clip to the origin.
  double crossing = 0, isolated = 0;
  for (const SingularCurve& c : set.curves)
    for (size_t i = 0; i + 1 < c.points.size(); ++i) {
      const Vec3 &p = c.points[i], &q = c.points[i + 1];
      if (c.kind == CurveKind::kDegenerate || p.norm() < kNearOrigin) continue;
      EXPECT_NEAR(p.y(), 0, 1e-12);
      EXPECT_NEAR(p.z(), p.x() * p.x() / 4, 1e-12);
      EXPECT_EQ(c.kind, p.x() < 0 ? CurveKind::kCrossing : CurveKind::kIsolated) << p.transpose();
      (p.x() < 0 ? crossing : isolated) += (q - p).norm();
    }
  EXPECT_GT(crossing, 0.9);  // the parabola's length from x = −1 to −0.1 is 0.93
  EXPECT_GT(isolated, 0.9);
  EXPECT_EQ(points_of(set, SingularPointKind::kClipEnd), 4);
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
