// FloaterSystem: the paper's claims (nodes covered, denser near the cusp, sheets crossing),
// animation, determinism across thread counts, and robustness where ∇F vanishes.
#include "zeroset/floaters/floaters.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "floater_test_support.h"
#include "support/equation.h"
#include "zeroset/error.h"
#include "zeroset/floaters/metrics.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

#ifdef _OPENMP
#include <omp.h>
#endif

namespace zeroset {
namespace {

using test::catalog_surface;

using test::with_clip;

// Runs until StepStats::converged, at most `limit` steps; returns the step it settled at or 0.
std::size_t settle(FloaterSystem& sys, std::size_t limit) {
  for (std::size_t k = 0; k < limit; ++k)
    if (sys.step().converged) return sys.steps_taken();
  return 0;
}

void expect_finite(const FloaterSystem& sys) {
  for (const Vec3& p : sys.positions()) ASSERT_TRUE(p.allFinite());
  for (const Vec3& n : sys.normals()) {
    ASSERT_TRUE(n.allFinite());
    ASSERT_NEAR(n.norm(), 1.0, 1e-9);
  }
  for (double r : sys.radii()) ASSERT_TRUE(std::isfinite(r) && r > 0);
}

void expect_finite(const StepStats& st) {
  EXPECT_TRUE(std::isfinite(st.median_residual));
  EXPECT_TRUE(std::isfinite(st.max_residual));
  EXPECT_TRUE(std::isfinite(st.rms_speed));
}

TEST(FloaterSystem, SettlesOnKummerWithEveryNodeCovered) {
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.5}});
  FloaterSystem sys(kummer, {.seed = 1});
  const std::size_t settled = settle(sys, 1000);
  ASSERT_GT(settled, 0u) << "did not settle in 1000 steps";
  const SampleMetrics m = measure_samples(kummer, sys.positions(), {.covering = false});
  EXPECT_LE(m.residual_median, 1e-6);
  ASSERT_EQ(m.singular.size(), 16u);
  for (const SingularCoverage& c : m.singular)
    EXPECT_LE(c.ratio, 0.5) << "node at " << c.point.transpose();
}

TEST(FloaterSystem, NodesAreCoveredWithoutSnappingToo) {
  // The dynamics alone (denser sampling near nodes) already bring floaters close to them;
  // snapping makes it exact. The least covered of the 16 nodes varies from run to run (its
  // distance to the nearest floater from 0.8 to 1.9 local spacings over 40 seeds), so this
  // looks at five.
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.5}});
  std::vector<double> worst;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    FloaterSystem sys(kummer, {.seed = seed, .snap_to_nodes = false});
    settle(sys, 600);
    const SampleMetrics m = measure_samples(kummer, sys.positions(), {.covering = false});
    ASSERT_EQ(m.singular.size(), 16u);
    EXPECT_LE(m.singular_ratio_max, 2.0) << "seed " << seed;
    worst.push_back(m.singular_ratio_max);
  }
  std::nth_element(worst.begin(), worst.begin() + 2, worst.end());
  EXPECT_LE(worst[2], 1.25);  // the median
}

TEST(FloaterSystem, ConeIsDenserNearTheCusp) {
  const Surface cone = catalog_surface("cone");
  MetricsOptions mo{.covering = false, .band_halfwidth = 0.25};  // a ball around the cusp
  FloaterSystem adaptive(cone, {.seed = 3});
  settle(adaptive, 600);
  const double dense = measure_samples(cone, adaptive.positions(), mo).band_density_ratio;
  EXPECT_GT(dense, 1.8);

  FloaterSystem uniform(
      cone, {.seed = 3, .radius_adapt = RadiusAdapt::kWitkinHeckbert, .snap_to_nodes = false});
  settle(uniform, 600);
  const double plain = measure_samples(cone, uniform.positions(), mo).band_density_ratio;
  EXPECT_LT(plain, 1.4);
  EXPECT_GT(dense, 1.5 * plain);
}

// Density within σ̂/2 of the planes' intersection line relative to elsewhere (paper figure 4).
// Without floaters held on the line (snap_to_nodes), which would fill the gap this measures.
double line_density(bool cos_weight, RadiusAdapt mode) {
  const Surface planes = catalog_surface("planes");
  FloaterSystem sys(planes, {.max_count = 4000,
                             .seed = 4,
                             .cos_weight = cos_weight,
                             .radius_adapt = mode,
                             .snap_to_nodes = false});
  settle(sys, 600);
  // Member by member: GCC 12 at -O1 sees the designated initializer's stop_token as
  // uninitialized (a false -Wmaybe-uninitialized).
  MetricsOptions mo;
  mo.covering = false;
  mo.band_halfwidth = sys.nominal_radius() / 2;
  return measure_samples(planes, sys.positions(), mo).band_density_ratio;
}

TEST(FloaterSystem, CosineWeightingLetsSheetsCrossWithoutAGap) {
  const double with = line_density(true, RadiusAdapt::kWitkinHeckbert);
  const double without = line_density(false, RadiusAdapt::kWitkinHeckbert);
  EXPECT_GT(with, 0.6);
  EXPECT_LT(without, 0.4);
  EXPECT_GT(with, 2.5 * without);
}

TEST(FloaterSystem, AnimationKeepsFloatersOnTheMovingSurface) {
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.02}});
  FloaterSystem sys(kummer, {.max_count = 1000, .seed = 5});
  settle(sys, 600);
  std::vector<double> q = {1.02};
  for (int k = 1; k <= 500; ++k) {
    q[0] = 1.02 + (2.44 - 1.02) * k / 500.0;
    const StepStats st = sys.step(q);
    expect_finite(st);
    ASSERT_LE(st.median_residual, 1e-3) << "step " << k << ", mu = " << q[0];
  }
  EXPECT_DOUBLE_EQ(sys.parameters()[0], 2.44);
  expect_finite(sys);
  EXPECT_GT(sys.size(), 100u);
}

TEST(FloaterSystem, ParameterVelocityTermTracksTheSurface) {
  // The same parameter sweep with the parameters jumping (no F_q·q̇ term) lags behind.
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.5}});
  FloaterOptions o{.max_count = 600, .seed = 6};
  FloaterSystem tracked(kummer, o), jumped(kummer, o);
  settle(tracked, 400);
  settle(jumped, 400);
  double worst_tracked = 0, worst_jumped = 0;
  for (int k = 1; k <= 50; ++k) {
    const std::vector<double> q = {1.5 + 0.01 * k};
    worst_tracked = std::max(worst_tracked, tracked.step(q).median_residual);
    jumped.set_parameters(q);
    worst_jumped = std::max(worst_jumped, jumped.step().median_residual);
  }
  EXPECT_LT(worst_tracked, 0.2 * worst_jumped);
}

TEST(FloaterSystem, SameResultOnOneAndTwoThreads) {
#ifndef _OPENMP
  GTEST_SKIP() << "built without OpenMP";
#else
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.5}});
  // Enough floaters for the steps to run in parallel (small systems run on one thread), and
  // enough steps for fissions, deaths and the estimators.
  auto run = [&](int threads) {
    omp_set_num_threads(threads);
    FloaterSystem sys(kummer, {.radius = 0.05, .max_count = 9000, .seed_count = 6000, .seed = 9});
    for (int k = 0; k < 40; ++k) sys.step();
    EXPECT_GT(sys.size(), 5000u);
    return std::vector<Vec3>(sys.positions().begin(), sys.positions().end());
  };
  const int saved = omp_get_max_threads();
  const std::vector<Vec3> one = run(1), two = run(2);
  omp_set_num_threads(saved);
  ASSERT_EQ(one.size(), two.size());
  for (std::size_t i = 0; i < one.size(); ++i) ASSERT_EQ(one[i], two[i]) << "floater " << i;
#endif
}

TEST(FloaterSystem, ResetReproducesAFreshStart) {
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.5}});
  FloaterSystem a(kummer, {.max_count = 500, .seed = 11});
  for (int k = 0; k < 30; ++k) a.step();
  a.reset();
  FloaterSystem b(kummer, {.max_count = 500, .seed = 11});
  for (int k = 0; k < 30; ++k) {
    a.step();
    b.step();
  }
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a.positions()[i], b.positions()[i]);
  a.reseed(12);
  a.step();
  b.step();
  EXPECT_NE(a.positions()[0], b.positions()[0]);
}

TEST(FloaterSystem, LoweringTheCapRemovesFloaters) {
  FloaterSystem sys(catalog_surface("sphere"), {.max_count = 800, .seed = 1});
  settle(sys, 400);
  ASSERT_GT(sys.size(), 200u);
  FloaterOptions o = sys.options();
  o.max_count = 100;
  sys.set_options(o);
  EXPECT_EQ(sys.size(), 100u);
  for (int k = 0; k < 50; ++k) EXPECT_LE(sys.step().count, 100u);
}

TEST(FloaterSystem, FollowsANewSurface) {
  FloaterSystem sys(catalog_surface("kummer", {{"mu", 1.5}}), {.max_count = 800, .seed = 4});
  for (int k = 0; k < 50; ++k) sys.step();
  const Surface torus = catalog_surface("torus");
  sys.set_surface(torus);
  EXPECT_EQ(sys.parameters().size(), 2u);
  settle(sys, 600);
  expect_finite(sys);
  EXPECT_GT(sys.size(), 100u);
  EXPECT_LT(measure_samples(torus, sys.positions(), {.covering = false}).residual_max, 1e-4);
}

TEST(FloaterSystem, FloatersStayInsideTheClip) {
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.5}});
  for (bool project : {true, false}) {
    FloaterSystem sys(kummer, {.max_count = 800, .seed = 2, .clip_projection = project});
    for (int k = 0; k < 150; ++k) sys.step();
    for (const Vec3& p : sys.positions()) ASSERT_TRUE(kummer.clip.contains(p, 1e-9));
    EXPECT_GT(sys.size(), 100u);
  }
}

TEST(FloaterSystem, OriginalMethodWithEveryExtensionOffStillSamples) {
  const Surface kummer = catalog_surface("kummer", {{"mu", 2.0}});
  FloaterSystem sys(kummer, {.max_count = 800,
                             .seed = 3,
                             .scaled_repulsion = false,
                             .cos_weight = false,
                             .radius_adapt = RadiusAdapt::kWitkinHeckbert,
                             .snap_to_nodes = false});
  settle(sys, 500);
  expect_finite(sys);
  const SampleMetrics m = measure_samples(kummer, sys.positions(), {.covering = false});
  EXPECT_LE(m.residual_median, 1e-5);
  for (double s : sys.max_radii()) EXPECT_DOUBLE_EQ(s, 1.5 * sys.nominal_radius());
}

TEST(FloaterSystem, SphereSamplingIsRegular) {
  FloaterSystem sys(catalog_surface("sphere"), {.max_count = 1500, .seed = 1});
  ASSERT_GT(settle(sys, 600), 0u);
  const SampleMetrics m = measure_samples(catalog_surface("sphere"), sys.positions());
  EXPECT_LT(m.spacing_cv, 0.1);
  EXPECT_LT(m.residual_max, 1e-5);
  EXPECT_LT(m.covering_relative, 1.0);
}

// --- robustness: nothing becomes NaN or infinite, whatever the surface or parameters ---------

void run_robust(const Surface& s, FloaterOptions o = {}, int steps = 200) {
  o.max_count = std::min<std::size_t>(o.max_count, 800);
  FloaterSystem sys(s, o);
  for (int k = 0; k < steps; ++k) {
    const StepStats st = sys.step();
    expect_finite(st);
    ASSERT_LE(st.count, o.max_count);
  }
  expect_finite(sys);
}

TEST(FloaterRobustness, DoubleSphereWhereTheGradientVanishesOnTheSurface) {
  // mu = 1/3: F = (8/3)(|x|² − 1/3)², ∇F = 0 all over the surface.
  const Surface s = catalog_surface("kummer", {{"mu", 1.0 / 3.0}});
  run_robust(s);
  FloaterSystem sys(s, {.max_count = 800});
  for (int k = 0; k < 200; ++k) sys.step();
  ASSERT_GT(sys.size(), 100u);
  for (const Vec3& p : sys.positions()) EXPECT_NEAR(p.norm(), std::sqrt(1.0 / 3.0), 1e-3);
}

TEST(FloaterRobustness, FourPlanes) { run_robust(catalog_surface("kummer", {{"mu", 3.0}})); }

TEST(FloaterRobustness, SurfaceThatIsASinglePoint) {
  run_robust(with_clip("x^2 + y^2 + z^2", "sphere:1"));
}

TEST(FloaterRobustness, ConstantFieldWithoutSurface) { run_robust(with_clip("1", "sphere:1")); }

TEST(FloaterRobustness, ZeroFieldEverywhere) { run_robust(with_clip("0 * x", "sphere:1")); }

TEST(FloaterRobustness, SurfaceEmptyInsideTheClip) {
  const Surface s = with_clip("sphere", "sphere:0.5");
  run_robust(s);
  FloaterSystem sys(s, {.max_count = 200});
  for (int k = 0; k < 300; ++k) sys.step();
  EXPECT_LT(sys.size(), 200u);  // strays keep being removed
}

TEST(FloaterRobustness, HugeAndTinyNominalRadius) {
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.5}});
  for (double r : {1e6, 10.0, 1e-6, 1e-12, 1e-300}) {
    SCOPED_TRACE(r);
    run_robust(kummer, {.radius = r}, 100);
  }
}

TEST(FloaterRobustness, ExtremeTimeStepsStayFinite) {
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.5}});
  // φ and γ scaled with dt as validate_settings asks: the same per-step pull and speed test.
  run_robust(kummer, {.dt = 10, .feedback = 15 * 0.03 / 10, .equilibrium_speed = 4 * 0.03 / 10},
             50);
  run_robust(kummer, {.dt = 1e-9}, 50);
}

// --- errors ------------------------------------------------------------------------------------

TEST(FloaterSystem, RejectsBadOptionsNamingThem) {
  const Surface kummer = catalog_surface("kummer");
  auto message = [&](FloaterOptions o) {
    try {
      FloaterSystem sys(kummer, o);
    } catch (const InvalidArgument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message({.radius = -1}).find("radius"), std::string::npos);
  EXPECT_NE(message({.radius = NAN}).find("radius"), std::string::npos);
  EXPECT_NE(message({.radius = 1e300}).find("radius"), std::string::npos);
  EXPECT_NE(message({.max_count = 0}).find("max_count"), std::string::npos);
  EXPECT_NE(message({.dt = 0}).find("dt"), std::string::npos);
  EXPECT_NE(message({.death_radius_factor = 1}).find("death_radius_factor"), std::string::npos);
  EXPECT_NE(message({.estimator_interval = 0}).find("estimator_interval"), std::string::npos);
  EXPECT_NE(message({.estimator_interval = 1001}).find("estimator_interval"), std::string::npos);
  // φ·dt ≥ 2: the pull's Euler step diverges; γ beyond max_step_fraction/dt or 0.
  EXPECT_NE(message({.feedback = 2 / 0.03}).find("feedback"), std::string::npos);
  EXPECT_NE(message({.dt = 1, .feedback = 2}).find("feedback"), std::string::npos);
  EXPECT_NE(message({.equilibrium_speed = 0}).find("equilibrium_speed"), std::string::npos);
  EXPECT_NE(message({.equilibrium_speed = 0.5 / 0.03 * 1.01}).find("equilibrium_speed"),
            std::string::npos);
  EXPECT_EQ(message({.feedback = 60, .equilibrium_speed = 16, .estimator_interval = 1000}), "");

  FloaterSystem sys(kummer, {.max_count = 100});
  FloaterOptions bad = sys.options();
  bad.radius_rate = -1;
  EXPECT_THROW(sys.set_options(bad), InvalidArgument);
  EXPECT_EQ(sys.options().radius_rate, 15);  // the old options stay
}

TEST(FloaterSystem, RejectsAnUnboundedClip) {
  EXPECT_THROW(FloaterSystem(surface_from_equation("x^2 + y^2 - 1")), BadInput);
}

TEST(FloaterSystem, RejectsWrongParameterValues) {
  FloaterSystem sys(catalog_surface("kummer"), {.max_count = 100});
  EXPECT_THROW(sys.step(std::vector<double>{1.0, 2.0}), InvalidArgument);
  EXPECT_THROW(sys.step(std::vector<double>{NAN}), InvalidArgument);
  EXPECT_THROW(sys.set_parameter("nu", 1.0), InvalidArgument);
  sys.set_parameter("mu", 2.0);
  EXPECT_EQ(sys.parameters()[0], 2.0);
}

TEST(RadiusAdapt, ParsesItsNames) {
  for (RadiusAdapt m : {RadiusAdapt::kWitkinHeckbert, RadiusAdapt::kCurvature,
                        RadiusAdapt::kSingular, RadiusAdapt::kMixed})
    EXPECT_EQ(parse_radius_adapt(to_string(m)), m);
  EXPECT_THROW(parse_radius_adapt("fast", "--radius-adapt"), InvalidArgument);
}

}  // namespace
}  // namespace zeroset
