// Sampling metrics: reference sampling, area, the singular-distance estimate, and the figures
// measure_samples reports, on point sets whose answers are known.
#include "zeroset/floaters/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "support/equation.h"
#include "zeroset/surface/scene.h"

namespace zeroset {
namespace {

using test::with_clip;

TEST(ReferenceSampling, PointsLieOnTheSurfaceInsideTheClip) {
  SurfaceOverrides o;
  o.params = {{"mu", 1.5}};
  const Surface kummer = resolve_surface("kummer", o);
  const ReferenceSampling ref = reference_sampling(kummer, {.count = 5000});
  ASSERT_EQ(ref.points.size(), 5000u);
  Evaluator ev(kummer.field);
  for (const Vec3& p : ref.points) {
    Vec3 g;
    const double f = ev.value_gradient(p, g);
    ASSERT_LT(std::abs(f) / g.norm(), 1e-8);
    ASSERT_TRUE(kummer.clip.contains(p, 1e-9));
  }
}

TEST(ReferenceSampling, IsDeterministic) {
  const Surface torus = resolve_surface("torus");
  const auto a = reference_sampling(torus, {.count = 2000, .seed = 3});
  const auto b = reference_sampling(torus, {.count = 2000, .seed = 3});
  ASSERT_EQ(a.points, b.points);
  EXPECT_EQ(a.area, b.area);
}

TEST(ReferenceSampling, AreaOfTheUnitSphereIsFourPi) {
  EXPECT_NEAR(estimate_area(resolve_surface("sphere")), 4 * std::numbers::pi,
              0.05 * 4 * std::numbers::pi);
}

TEST(ReferenceSampling, AreaOfTwoPlanesInABall) {
  // Two planes through the centre of the unit ball: two unit disks.
  EXPECT_NEAR(estimate_area(resolve_surface("planes")), 2 * std::numbers::pi,
              0.05 * 2 * std::numbers::pi);
}

TEST(ReferenceSampling, IsUniformInArea) {
  // On the unit sphere a uniform sampling puts a fraction (1 - cos θ)/2 within angle θ of a pole.
  const ReferenceSampling ref = reference_sampling(resolve_surface("sphere"), {.count = 10000});
  std::size_t cap = 0;
  for (const Vec3& p : ref.points) cap += p.z() > std::cos(0.5) ? 1 : 0;
  const double expected = (1 - std::cos(0.5)) / 2;  // 612 of 10,000 points, ± 25 by chance
  EXPECT_NEAR(static_cast<double>(cap) / 10000.0, expected, 0.15 * expected);
}

TEST(ReferenceSampling, EmptySurfaceGivesNothing) {
  const ReferenceSampling ref = reference_sampling(with_clip("sphere", "sphere:0.5"),
                                                   {.count = 100, .max_candidates = 50000});
  EXPECT_TRUE(ref.points.empty());
  EXPECT_EQ(ref.area, 0);
  EXPECT_EQ(ref.candidates, 50000u);
}

// Points of the Fibonacci lattice on the unit sphere: nearly uniform.
std::vector<Vec3> fibonacci_sphere(int n) {
  std::vector<Vec3> out;
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - (i + 0.5) * 2.0 / n, r = std::sqrt(1 - z * z);
    out.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  return out;
}

TEST(MeasureSamples, RegularSphereSampling) {
  const Surface sphere = resolve_surface("sphere");
  const auto pts = fibonacci_sphere(2000);
  const SampleMetrics m = measure_samples(sphere, pts);
  EXPECT_EQ(m.count, 2000u);
  EXPECT_LT(m.residual_max, 1e-12);
  // Spacing of 2000 points on a sphere of area 4π is about sqrt(4π/2000/0.87) ≈ 0.085.
  EXPECT_NEAR(m.spacing_mean, 0.08, 0.01);
  EXPECT_LT(m.spacing_cv, 0.1);
  EXPECT_GT(m.covering_radius, 0.4 * m.spacing_mean);
  EXPECT_LT(m.covering_relative, 1.0);
}

TEST(MeasureSamples, CoveringRadiusSeesAHole) {
  const Surface sphere = resolve_surface("sphere");
  std::vector<Vec3> pts;
  for (const Vec3& p : fibonacci_sphere(2000))
    if (p.z() < 0.8) pts.push_back(p);  // a cap of angular radius acos(0.8) ≈ 0.64 missing
  const SampleMetrics m = measure_samples(sphere, pts);
  EXPECT_NEAR(m.covering_radius, 2 * std::sin(std::acos(0.8) / 2), 0.03);
}

TEST(MeasureSamples, SingularPointCoverage) {
  const Surface cone = resolve_surface("cone");  // singular point: the cusp at the origin
  std::vector<Vec3> pts;
  for (int k = 1; k <= 10; ++k)
    for (int a = 0; a < 12; ++a) {
      const double r = 0.1 * k, t = a * std::numbers::pi / 6;
      pts.emplace_back(r * std::cos(t), r * std::sin(t), r);
    }
  SampleMetrics m = measure_samples(cone, pts, {.covering = false});
  ASSERT_EQ(m.singular.size(), 1u);
  EXPECT_NEAR(m.singular[0].distance, 0.1 * std::sqrt(2.0), 1e-12);
  EXPECT_GT(m.singular[0].ratio, 1.0);
  pts.push_back(Vec3::Zero());
  m = measure_samples(cone, pts, {.covering = false});
  EXPECT_EQ(m.singular_ratio_max, 0);
}

TEST(MeasureSamples, ResidualLeavesOutTheSingularBalls) {
  const Surface cone = resolve_surface("cone");
  const std::vector<Vec3> pts = {Vec3(0.5, 0, 0.5), Vec3(0, 0.5, 0.5 + 1e-3), Vec3(1e-3, 0, 0)};
  const SampleMetrics m =
      measure_samples(cone, pts, {.singular_exclusion = 0.1, .covering = false});
  EXPECT_EQ(m.residual_excluded, 1u);
  EXPECT_NEAR(m.residual_max, 1e-3 / std::sqrt(2.0), 1e-5);
}

TEST(MeasureSamples, BandDensityIsOneForUniformSamplesAndZeroForAGap) {
  const Surface planes = resolve_surface("planes");
  const ReferenceSampling other = reference_sampling(planes, {.count = 5000, .seed = 99});
  MetricsOptions mo{.covering = false, .band_halfwidth = 0.05};
  mo.reference.count = 5000;
  const SampleMetrics uniform = measure_samples(planes, other.points, mo);
  EXPECT_NEAR(uniform.band_density_ratio, 1.0, 0.1);
  std::vector<Vec3> gap;
  for (const Vec3& p : other.points)
    if (std::hypot(p.x(), p.y()) > 0.1) gap.push_back(p);  // nothing near the line x = y = 0
  EXPECT_EQ(measure_samples(planes, gap, mo).band_density_ratio, 0);
}

}  // namespace
}  // namespace zeroset
