#include "zeroset/surface/analysis.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "zeroset/expr/parse.h"

namespace zeroset {
namespace {

TEST(Residual, IsTheFirstOrderDistanceWithoutInfinities) {
  EXPECT_EQ(residual(0, 0), 0);  // on the surface, even where ∇F = 0
  EXPECT_DOUBLE_EQ(residual(-3, 2), 1.5);
  constexpr double kMax = std::numeric_limits<double>::max();
  EXPECT_EQ(residual(1, 0), kMax);  // ∇F = 0 off the surface
  EXPECT_EQ(residual(std::nan(""), 1), kMax);
  EXPECT_EQ(residual(1, std::numeric_limits<double>::infinity()), kMax);
  EXPECT_EQ(residual(1e300, 1e-300), kMax);  // overflows
  EXPECT_TRUE(has_residual(1, 2));
  EXPECT_FALSE(has_residual(1, 0));
  EXPECT_FALSE(has_residual(std::nan(""), 2));
}

TEST(CriticalStep, ReachesTheConeTip) {
  // F = x² + y² − z²: ∇F = 2(x, y, −z), Hessian diag(2, 2, −2): r = p exactly.
  Evaluator ev(compile_field("x^2 + y^2 - z^2"));
  const Vec3 p(0.3, -0.2, 0.5);
  const FieldSample s = ev.sample(p, Derivatives::kHessian);
  const CriticalStep c = critical_step(s.gradient, s.hessian);
  EXPECT_TRUE(c.reaches);
  EXPECT_NEAR((c.step - p).norm(), 0, 1e-14);
  EXPECT_DOUBLE_EQ(c.smallest, 2);
  EXPECT_DOUBLE_EQ(c.largest, 2);
  EXPECT_NEAR(singular_distance(s.gradient, s.hessian), p.norm(), 1e-12);
  const auto fast = regular_critical_step(s.gradient, s.hessian);
  ASSERT_TRUE(fast.has_value());
  EXPECT_EQ(*fast, c.step);  // the same step without the eigenvalues
}

TEST(CriticalStep, LeastSquaresOnTheLineOfTwoPlanes) {
  // F = x·y: ∇F = (y, x, 0), singular Hessian; the singular set is the z axis.
  Mat3 h = Mat3::Zero();
  h(0, 1) = h(1, 0) = 1;
  const Vec3 p(0.4, 0.3, 7.0);
  const CriticalStep c = critical_step(Vec3(p.y(), p.x(), 0), h);
  EXPECT_TRUE(c.reaches);
  EXPECT_NEAR((c.step - Vec3(0.4, 0.3, 0)).norm(), 0, 1e-12);
  EXPECT_NEAR(singular_distance(Vec3(p.y(), p.x(), 0), h), 0.5, 1e-12);
  EXPECT_FALSE(regular_critical_step(Vec3(p.y(), p.x(), 0), h).has_value());
}

TEST(CriticalStep, DoesNotReachWhereTheGradientCannotVanish) {
  // F = x + y²: ∇F = (1, 2y, 0) never vanishes; the Hessian has a null direction along x.
  Mat3 h = Mat3::Zero();
  h(1, 1) = 2;
  const CriticalStep c = critical_step(Vec3(1, 0.6, 0), h);
  EXPECT_FALSE(c.reaches);
  EXPECT_NEAR((c.step - Vec3(0, 0.3, 0)).norm(), 0, 1e-15);  // the other directions' part
  EXPECT_TRUE(std::isinf(singular_distance(Vec3(1, 0.6, 0), h)));
  EXPECT_TRUE(std::isinf(singular_distance(Vec3(1, 0, 0), Mat3::Zero())));  // a plane
  EXPECT_EQ(singular_distance(Vec3::Zero(), h), 0);
  // The pseudo-inverse step goes on over the other directions.
  EXPECT_NEAR((pseudo_inverse_step(Vec3(1, 0.6, 0), h) - Vec3(0, 0.3, 0)).norm(), 0, 1e-15);
  EXPECT_TRUE(std::isinf(pseudo_inverse_step(Vec3(1, 0, 0), Mat3::Zero()).norm()));
}

TEST(FindCriticalPoint, FindsTheConeNodeAndNotTheCylinderAxis) {
  Evaluator cone(compile_field("x^2 + y^2 - z^2 + 0.1*x^3"));
  const auto node =
      find_critical_point(cone, Vec3(0.05, -0.04, 0.03), {.reach = 1, .min_conditioning = 1e-3});
  ASSERT_TRUE(node.has_value());
  EXPECT_LT(node->point.norm(), 1e-14);
  EXPECT_LT(std::abs(node->value), 1e-26);
  EXPECT_NEAR(node->largest, 2, 1e-12);
  // Out of reach: no answer.
  EXPECT_FALSE(find_critical_point(cone, Vec3(0.5, 0.5, 0.5), {.reach = 0.1}).has_value());
  // F = x² + y² − 1 has ∇F = 0 on the whole z axis: degenerate, so only found when allowed.
  Evaluator cylinder(compile_field("x^2 + y^2 - 1"));
  EXPECT_FALSE(
      find_critical_point(cylinder, Vec3(0.1, 0.2, 0.7), {.min_conditioning = 1e-3}).has_value());
  const auto axis = find_critical_point(cylinder, Vec3(0.1, 0.2, 0.7), {.iterations = 30});
  ASSERT_TRUE(axis.has_value());
  EXPECT_NEAR(axis->point.head<2>().norm(), 0, 1e-14);
  EXPECT_NEAR(axis->point.z(), 0.7, 1e-14);
  EXPECT_NEAR(axis->value, -1, 1e-14);  // a critical point off the surface: the caller judges
}

TEST(ProjectOntoSurface, LandsOnTheSphere) {
  Evaluator ev(compile_field("x^2 + y^2 + z^2 - 1"));
  Vec3 p(0.3, 0.9, -0.6);
  ASSERT_TRUE(project_onto_surface(ev, p, 1e-12, 1));
  Vec3 g;
  const double f = ev.value_gradient(p, g);
  EXPECT_LT(residual(f, g.norm()), 1e-12);
  EXPECT_NEAR((p.normalized() - Vec3(0.3, 0.9, -0.6).normalized()).norm(), 0, 1e-12);
  // Too far to go: false.
  Vec3 q(3, 0, 0);
  EXPECT_FALSE(project_onto_surface(ev, q, 1e-12, 0.5));
  // From the centre (∇F = 0, F ≠ 0) there is no Newton step.
  Vec3 c = Vec3::Zero();
  EXPECT_FALSE(project_onto_surface(ev, c, 1e-12, 10));
  // One step is the Newton step.
  const Vec3 s = surface_newton_step(3, Vec3(0, 2, 0));
  EXPECT_EQ(s, Vec3(0, -1.5, 0));
}

TEST(ClipCurve, ProjectionLandsOnBothSurfaces) {
  // The unit sphere cut by the plane z ≤ 0.5: the curve is the circle of radius √0.75 at z = 0.5.
  Evaluator ev(compile_field("x^2 + y^2 + z^2 - 1"));
  Clip clip;
  clip.add("plane:0,0,1,0.5");
  const Vec3 start(0.7, 0.2, 0.62);
  const Vec3 p = project_onto_clip_curve(ev, clip, start, 1);
  Vec3 g;
  EXPECT_LT(std::abs(ev.value_gradient(p, g)), 1e-14);
  EXPECT_LT(std::abs(clip.value(p)), 1e-15);
  EXPECT_LT((p - start).norm(), 0.3);
  // Out of reach: only snapped onto the clip.
  const Vec3 q = project_onto_clip_curve(ev, clip, Vec3(0.1, 0, 0.7), 0.01);
  EXPECT_NEAR((q - Vec3(0.1, 0, 0.5)).norm(), 0, 1e-15);
  EXPECT_NEAR((snap_to_clip(clip, Vec3(0.1, 0, 0.7)) - Vec3(0.1, 0, 0.5)).norm(), 0, 1e-15);
}

TEST(ClipCurve, BoundedStepsApproachTheCurveAlongTheClip) {
  // A sphere clip of radius 1.2 around the plane z = 0.3: the curve is a circle on the sphere.
  Evaluator ev(compile_field("z - 0.3"));
  const Clip clip = Clip::sphere(1.2);
  Vec3 p = clip.project(Vec3(0, 1.5, 0.6));  // on the sphere, off the plane
  const double before = std::abs(p.z() - 0.3);
  p = step_onto_clip_curve(ev, clip, p, 0.05, 1);  // one step, capped
  EXPECT_NEAR(std::abs(p.z() - 0.3), before - 0.05, 0.01);
  EXPECT_NEAR(clip.value(p), 0, 1e-15);
  for (int k = 0; k < 10; ++k) p = step_onto_clip_curve(ev, clip, p, 1.0);
  EXPECT_NEAR(p.z(), 0.3, 1e-12);
  EXPECT_NEAR(clip.value(p), 0, 1e-15);
}

}  // namespace
}  // namespace zeroset
