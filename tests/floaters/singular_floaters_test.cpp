// Floaters on surfaces whose singular set has curves (docs/algorithms.md B.7): they settle, every
// special point carries a floater, and no gap along a curve is wider than the local spacing.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <set>
#include <string>

#include "floater_test_support.h"
#include "zeroset/floaters/floaters.h"
#include "zeroset/floaters/metrics.h"
#include "zeroset/surface/scene.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset {
namespace {

using test::catalog_surface;

struct Settled {
  std::size_t step = 0;  // 0: not settled within the limit
  SingularSet set;
  SingularSetCoverage coverage;
};

Settled settle_and_measure(const Surface& s, std::size_t max_count, std::uint64_t seed) {
  FloaterSystem sys(s, {.max_count = max_count, .seed = seed});
  Settled out;
  for (std::size_t k = 0; k < 3000 && out.step == 0; ++k)
    if (sys.step().converged) out.step = sys.steps_taken();
  out.set = find_singular_set(s);
  out.coverage = measure_singular_coverage(out.set, sys.positions());
  return out;
}

void expect_covered(const Settled& r, const char* name) {
  SCOPED_TRACE(name);
  EXPECT_GT(r.step, 0u) << "did not settle within 3000 steps";
  ASSERT_FALSE(r.set.curves.empty());
  for (std::size_t k = 0; k < r.set.points.size(); ++k) {
    if (r.set.points[k].kind == SingularPointKind::kPinch ||
        r.set.points[k].kind == SingularPointKind::kTriple) {
      EXPECT_LE(r.coverage.point_ratio[k], 0.5)
          << to_string(r.set.points[k].kind) << " point " << k;
    }
  }
  for (std::size_t k = 0; k < r.set.curves.size(); ++k)
    EXPECT_LE(r.coverage.curve_gap[k], 1.0) << to_string(r.set.curves[k].kind) << " curve " << k;
}

TEST(SingularFloaters, RomanSettlesWithItsPointsAndCurvesCovered) {
  for (std::uint64_t seed : {1, 2}) {
    const Settled r = settle_and_measure(catalog_surface("roman"), 1000, seed);
    EXPECT_EQ(r.set.points_of(SingularPointKind::kPinch).size(), 6u);
    EXPECT_EQ(r.set.points_of(SingularPointKind::kTriple).size(), 1u);
    expect_covered(r, "roman");
  }
}

TEST(SingularFloaters, WhitneySettlesWithItsHandleSampled) {
  for (std::uint64_t seed : {1, 2}) {
    const Settled r = settle_and_measure(catalog_surface("whitney"), 1000, seed);
    EXPECT_EQ(r.set.count(CurveKind::kIsolated), 1);
    expect_covered(r, "whitney");
  }
}

TEST(SingularFloaters, CrossingPlanesAreCoveredAlongTheirLines) {
  expect_covered(settle_and_measure(catalog_surface("planes"), 1000, 3), "planes");
  expect_covered(settle_and_measure(catalog_surface("kummer", {{"mu", 3.0}}), 1500, 3),
                 "kummer mu = 3");
}

// No gap along a curve is wider than the spacing of the sheets around it, over several seeds
// and populations: the whiskers of Roman (isolated curves from a pinch point to the clip),
// where the sheets folding into the pinch point pack tighter than the chain was placed (seed
// 8 at 2,000 floaters left a gap of 1.04 spacings), and Whitney's handle and half-line.
TEST(SingularFloaters, NoGapWiderThanTheSheetsSpacingOverSeeds) {
  const Surface roman = catalog_surface("roman"), whitney = catalog_surface("whitney");
  for (std::uint64_t seed : {6, 7, 8, 9}) {
    SCOPED_TRACE(seed);
    const Settled r = settle_and_measure(roman, 2000, seed);
    EXPECT_GT(r.step, 0u);
    EXPECT_LE(r.coverage.curve_gap_max, 1.0);
  }
  // Seeds 2 and 4 left gaps of 0.97 and 0.94 before the chains followed the sheets.
  for (std::uint64_t seed : {2, 4}) {
    SCOPED_TRACE(seed);
    const Settled w = settle_and_measure(whitney, 1000, seed);
    EXPECT_GT(w.step, 0u);
    EXPECT_LE(w.coverage.curve_gap_max, 1.0);
  }
}

// Floaters on the singular set found (to rounding) stay on it while the sheets settle around.
TEST(SingularFloaters, FloatersOnACurveStayOnIt) {
  const Surface whitney = catalog_surface("whitney");
  const SingularSet set = find_singular_set(whitney);
  FloaterSystem sys(whitney, {.max_count = 800, .seed = 5});
  for (int k = 0; k < 100; ++k) sys.step();
  const double tiny = 1e-9 * whitney.scene_radius();
  std::set<std::uint64_t> held;
  for (std::size_t i = 0; i < sys.size(); ++i)
    if (set.distance(sys.positions()[i]) < tiny) held.insert(sys.ids()[i]);
  EXPECT_GT(held.size(), 10u);
  for (int k = 0; k < 200; ++k) sys.step();
  std::size_t still = 0;
  for (std::size_t i = 0; i < sys.size(); ++i)
    if (held.count(sys.ids()[i])) {
      ++still;
      EXPECT_LT(set.distance(sys.positions()[i]), tiny);
    }
  EXPECT_EQ(still, held.size());
}

// The held floaters follow the set when the parameters move: none is left on the old line, and
// the new line is covered once the parameters have come to rest.
TEST(SingularFloaters, FollowTheSetWhenParametersChange) {
  const Surface planes = catalog_surface("planes");
  FloaterSystem sys(planes, {.max_count = 800, .seed = 6});
  for (int k = 0; k < 200; ++k) sys.step();
  const std::vector<double> moved{0.25};
  sys.set_parameters(moved);
  for (int k = 0; k < 400; ++k) sys.step();
  const Surface now = catalog_surface("planes", {{"a", 0.25}});
  const SingularSet old_set = find_singular_set(planes), new_set = find_singular_set(now);
  const double tiny = 1e-9;
  std::size_t on_old = 0, on_new = 0;
  for (const Vec3& p : sys.positions()) {
    on_old += old_set.distance(p) < tiny ? 1 : 0;
    on_new += new_set.distance(p) < tiny ? 1 : 0;
  }
  EXPECT_EQ(on_old, 0u);
  EXPECT_GT(on_new, 5u);
  EXPECT_LE(measure_singular_coverage(new_set, sys.positions()).curve_gap_max, 1.0);
}

// Without holding (the paper's method) nothing is placed on the set.
TEST(SingularFloaters, NoSnapLeavesTheSetToTheDynamics) {
  const Surface whitney = catalog_surface("whitney");
  const SingularSet set = find_singular_set(whitney);
  FloaterSystem sys(whitney, {.max_count = 500, .seed = 7, .snap_to_nodes = false});
  for (int k = 0; k < 16; ++k) sys.step();
  for (const Vec3& p : sys.positions()) EXPECT_GT(set.distance(p), 1e-9);
}

TEST(SingularSetCoverage, SeesAGapAlongACurve) {
  SingularSet set;
  set.curves.push_back({CurveKind::kCrossing, {Vec3(0, 0, 0), Vec3(1, 0, 0)}, false});
  set.points.push_back({Vec3(0, 0, 0), SingularPointKind::kClipEnd});
  // A sheet sampled at spacing 0.05 in the plane z = 0.1 (off the set), and samples on the
  // curve every 0.04, with one missing around x = 0.5 (a gap of 0.12).
  std::vector<Vec3> samples;
  for (int i = -5; i <= 25; ++i)
    for (int j = -5; j <= 5; ++j) samples.emplace_back(0.05 * i, 0.05 * j, 0.1);
  for (int i = 0; i <= 25; ++i)
    if (std::abs(i * 0.04 - 0.5) > 0.05) samples.emplace_back(0.04 * i, 0, 0);
  const SingularSetCoverage c = measure_singular_coverage(set, samples);
  ASSERT_EQ(c.curve_gap.size(), 1u);
  EXPECT_NEAR(c.curve_gap[0], 0.12 / 0.05, 0.1);
  EXPECT_NEAR(c.point_ratio[0], 0.0, 1e-12);
}

}  // namespace
}  // namespace zeroset
