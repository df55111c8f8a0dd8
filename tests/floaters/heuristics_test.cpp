// zeroset's heuristics beyond the papers, each switched off (FloaterOptions: clip_newton,
// average_radius_factor, local_nominal_radius, energy_taper, fission_offset), and the radius
// factor μ_i of each RadiusAdapt mode: every switch changes what docs/floaters.md says it does.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "floater_test_support.h"
#include "zeroset/floaters/floaters.h"
#include "zeroset/floaters/settings.h"

namespace zeroset {
namespace {

using test::catalog_surface;

FloaterSystem settled(const Surface& s, const FloaterOptions& o, int steps) {
  FloaterSystem sys(s, o);
  for (int k = 0; k < steps; ++k) sys.step();
  return sys;
}

// Floaters per unit area within slant distance [a, b) of the cone's apex: the catalog cone
// x² + y² = z², 0 ≤ z ≤ 1, has area π(b² − a²)/√2 there.
double cone_density(const FloaterSystem& sys, double a, double b) {
  std::size_t n = 0;
  for (const Vec3& p : sys.positions()) n += p.norm() >= a && p.norm() < b;
  return static_cast<double>(n) / (std::numbers::pi * (b * b - a * a) / std::numbers::sqrt2);
}

// The density near the apex (slant distance below 0.25) over that farther out (0.4 to 0.9).
double cone_apex_ratio(const FloaterSystem& sys) {
  return cone_density(sys, 0, 0.25) / cone_density(sys, 0.4, 0.9);
}

// |F|/|∇F| of the cone at p.
double cone_residual(const Vec3& p) {
  const double f = p.x() * p.x() + p.y() * p.y() - p.z() * p.z();
  return std::abs(f) / (2 * p.norm());
}

TEST(FloaterSwitches, DefaultsAreOnAndRoundTrip) {
  const FloaterOptions o;
  EXPECT_TRUE(o.clip_newton && o.average_radius_factor && o.local_nominal_radius &&
              o.energy_taper && o.fission_offset);
  EXPECT_EQ(o.feedback, 15);
  EXPECT_EQ(o.equilibrium_speed, 4);
  EXPECT_EQ(o.estimator_interval, 8);
  const nlohmann::json j = floater_settings_to_json(o);
  for (const char* key : {"clip_newton", "average_radius_factor", "local_nominal_radius",
                          "energy_taper", "fission_offset"})
    EXPECT_EQ(j.at(key), true) << key;
  FloaterOptions off;
  nlohmann::json all_off = j;
  for (const char* key : {"clip_newton", "average_radius_factor", "local_nominal_radius",
                          "energy_taper", "fission_offset"})
    all_off[key] = false;
  all_off["feedback"] = 20;
  all_off["equilibrium_speed"] = 3;
  all_off["estimator_interval"] = 5;
  apply_floater_settings(all_off, off, "test");
  EXPECT_EQ(floater_settings_to_json(off), all_off);
  EXPECT_FALSE(off.clip_newton || off.average_radius_factor || off.local_nominal_radius ||
               off.energy_taper || off.fission_offset);
}

// The cone ends at the clip plane z = 1: with the Newton steps along the boundary the floaters
// there lie on F = 0; with the projection alone they are pushed out and back every step and
// stay off the surface.
TEST(FloaterSwitches, ClipNewtonPutsBoundaryFloatersOnTheSurface) {
  const Surface cone = catalog_surface("cone");
  auto boundary_residual = [&](bool newton) {
    const FloaterSystem sys =
        settled(cone, {.max_count = 600, .seed = 3, .clip_newton = newton}, 300);
    double worst = 0;
    std::size_t on_boundary = 0;
    for (const Vec3& p : sys.positions())
      if (p.z() > 1 - 1e-9) {
        worst = std::max(worst, cone_residual(p));
        ++on_boundary;
      }
    EXPECT_GT(on_boundary, 5u) << newton;
    return worst / sys.nominal_radius();
  };
  const double with = boundary_residual(true), without = boundary_residual(false);
  RecordProperty("residual_with", std::to_string(with));
  RecordProperty("residual_without", std::to_string(without));
  EXPECT_LT(with, 1e-4);
  EXPECT_GT(without, 1e-3);
  EXPECT_GT(without, 100 * with);
}

// μ_i on the cone x² + y² − z², whose Newton step towards ∇F = 0 is F_xx⁻¹F_x = p exactly
// (docs/algorithms.md B.3): β_i = min(|p_i|/γ_s, 1), and with radius_adapt singular and no
// grading σ_max^i = μ_i σ_max with μ_i = clamp(β_i, min_radius_factor, 1) (B.4), averaged with
// the previous μ_i (1 at the start) unless average_radius_factor is off.
TEST(FloaterSwitches, RadiusFactorOnTheConeFollowsTheFormula) {
  const Surface cone = catalog_surface("cone");
  for (const bool average : {true, false}) {
    SCOPED_TRACE(average);
    const FloaterOptions o{.max_count = 800,
                           .seed = 5,
                           .radius_adapt = RadiusAdapt::kSingular,
                           .average_radius_factor = average,
                           .estimator_interval = 4,
                           .singular_scale = 0.6,
                           .snap_to_nodes = false,
                           .min_radius_factor = 0.1,
                           .radius_grading = 0};
    FloaterSystem sys(cone, o);
    for (int k = 0; k < 40; ++k) sys.step();  // on the surface, several refreshes behind
    const double smax = o.max_radius_factor * sys.nominal_radius();
    // μ_i before the refresh of step 40, and the positions it is computed at.
    std::unordered_map<std::uint64_t, std::pair<Vec3, double>> before;
    for (std::size_t i = 0; i < sys.size(); ++i)
      before[sys.ids()[i]] = {sys.positions()[i], sys.max_radii()[i] / smax};
    sys.step();
    std::size_t checked = 0, clamped_low = 0, clamped_high = 0;
    double worst = 0;
    for (std::size_t i = 0; i < sys.size(); ++i) {
      const auto it = before.find(sys.ids()[i]);
      if (it == before.end()) continue;  // born in this step
      const auto [p, mu_before] = it->second;
      const double beta = std::min(p.norm() / o.singular_scale, 1.0);
      const double fresh = std::clamp(beta, o.min_radius_factor, 1.0);
      const double want = average ? 0.5 * (mu_before + fresh) : fresh;
      worst = std::max(worst, std::abs(sys.max_radii()[i] / smax - want));
      clamped_low += beta < o.min_radius_factor;
      clamped_high += beta >= 1;
      ++checked;
    }
    EXPECT_GT(checked, 300u);
    EXPECT_GT(clamped_low, 0u);   // within 0.06 of the apex
    EXPECT_GT(clamped_high, 0u);  // beyond 0.6
    EXPECT_LT(worst, 1e-9);
  }
}

// With the average, μ_i moves halfway to each new estimate: on the curvature estimator, whose
// perimeter points are random, the fission radius jumps less from one refresh to the next.
TEST(FloaterSwitches, AveragingSteadiesTheRadiusFactor) {
  const Surface kummer = catalog_surface("kummer", {{"mu", 1.5}});
  auto mean_jump = [&](bool average) {
    FloaterSystem sys(kummer, {.max_count = 800,
                               .seed = 2,
                               .radius_adapt = RadiusAdapt::kCurvature,
                               .average_radius_factor = average,
                               .radius_grading = 0});
    for (int k = 0; k < 160; ++k) sys.step();
    double sum = 0;
    std::size_t count = 0;
    for (int refresh = 0; refresh < 5; ++refresh) {
      std::unordered_map<std::uint64_t, double> before;
      for (std::size_t i = 0; i < sys.size(); ++i) before[sys.ids()[i]] = sys.max_radii()[i];
      for (int k = 0; k < 8; ++k) sys.step();
      for (std::size_t i = 0; i < sys.size(); ++i)
        if (const auto it = before.find(sys.ids()[i]); it != before.end()) {
          sum += std::abs(sys.max_radii()[i] - it->second) / sys.nominal_radius();
          ++count;
        }
    }
    return sum / static_cast<double>(count);
  };
  const double with = mean_jump(true), without = mean_jump(false);
  RecordProperty("jump_with", std::to_string(with));
  RecordProperty("jump_without", std::to_string(without));
  EXPECT_LT(with, 0.75 * without);
}

// Near the apex σ_max^i is small; with the paper's σ̂ in the death test the floaters there
// are below δσ̂ and die, and fission (above σ_max^i) makes them again: a churn that never
// settles. The local σ̂_i stops it.
TEST(FloaterSwitches, LocalNominalRadiusStopsTheChurnNearASingularPoint) {
  const Surface cone = catalog_surface("cone");
  auto deaths = [&](bool local) {
    FloaterSystem sys(cone, {.max_count = 1500, .seed = 4, .local_nominal_radius = local});
    for (int k = 0; k < 200; ++k) sys.step();
    std::size_t dead = 0;
    for (int k = 0; k < 200; ++k) dead += sys.step().deaths;
    // The refinement near the apex is there either way.
    EXPECT_GT(cone_apex_ratio(sys), 2) << local;
    return dead;
  };
  const std::size_t with = deaths(true), without = deaths(false);
  RecordProperty("deaths_with", std::to_string(with));
  RecordProperty("deaths_without", std::to_string(without));
  EXPECT_GT(without, 10 * with + 100);
}

// The plain Gaussian has more energy at a given distance than the tapered one, so radius
// adaptation settles at smaller radii for the same spacing.
TEST(FloaterSwitches, WithoutTaperRadiiAreSmallerForTheSameSpacing) {
  const Surface sphere = catalog_surface("sphere");
  auto radius_per_spacing = [&](bool taper) {
    const FloaterSystem sys = settled(sphere,
                                      {.max_count = 800,
                                       .seed = 6,
                                       .energy_taper = taper,
                                       .radius_adapt = RadiusAdapt::kWitkinHeckbert},
                                      300);
    const auto pos = sys.positions();
    double spacing = 0, radius = 0;
    for (std::size_t i = 0; i < pos.size(); ++i) {
      double nearest = std::numeric_limits<double>::infinity();
      for (std::size_t j = 0; j < pos.size(); ++j)
        if (j != i) nearest = std::min(nearest, (pos[i] - pos[j]).norm());
      spacing += nearest;
      radius += sys.radii()[i];
    }
    return radius / spacing;
  };
  const double with = radius_per_spacing(true), without = radius_per_spacing(false);
  RecordProperty("with", std::to_string(with));
  RecordProperty("without", std::to_string(without));
  EXPECT_LT(without, 0.95 * with);
}

// A fission child starts 0.25σ to 0.5σ from its parent (σ the parent's radius before it
// halves, √2 times the child's), or, without the offset, where its parent is.
TEST(FloaterSwitches, FissionOffsetPlacesTheChildAwayFromItsParent) {
  const Surface sphere = catalog_surface("sphere");
  for (const bool offset : {true, false}) {
    SCOPED_TRACE(offset);
    FloaterSystem sys(sphere, {.max_count = 600, .seed = 8, .fission_offset = offset});
    std::unordered_set<std::uint64_t> known(sys.ids().begin(), sys.ids().end());
    std::size_t children = 0;
    double closest = std::numeric_limits<double>::infinity(), farthest = 0;
    for (int k = 0; k < 60 && children < 50; ++k) {
      sys.step();
      const auto pos = sys.positions();
      for (std::size_t i = 0; i < sys.size(); ++i) {
        if (known.count(sys.ids()[i])) continue;
        ++children;
        double nearest = std::numeric_limits<double>::infinity();
        for (std::size_t j = 0; j < sys.size(); ++j)
          if (j != i) nearest = std::min(nearest, (pos[i] - pos[j]).norm());
        const double parent_radius = std::numbers::sqrt2 * sys.radii()[i];
        closest = std::min(closest, nearest / parent_radius);
        farthest = std::max(farthest, nearest / parent_radius);
      }
      known.insert(sys.ids().begin(), sys.ids().end());
    }
    ASSERT_GT(children, 20u);
    RecordProperty(offset ? "closest_with" : "closest_without", std::to_string(closest));
    RecordProperty(offset ? "farthest_with" : "farthest_without", std::to_string(farthest));
    if (offset) {
      // On the sphere the tangential offset shrinks a little as F is re-evaluated; no move
      // follows the fission within its step.
      EXPECT_GT(closest, 0.2);
      EXPECT_LT(farthest, 0.51);
    } else {
      EXPECT_EQ(farthest, 0.0);
    }
  }
}

// Curvature only (μ_i = α_i): a thin tube (y² + z² = 0.05², curvature 20 across it) and a
// plane (z = 0.8, curvature 0) in one surface, with σ̂ = 0.12: the curvature estimator sees the
// tube bend within a floater's radius and samples it more densely, relative to the plane, than
// Witkin–Heckbert's one global fission radius does.
TEST(RadiusAdaptModes, CurvatureOnlyIsDenserWhereCurvatureIsHigh) {
  SurfaceOverrides so;
  so.clip_specs = {"sphere:1.5"};
  const Surface tube_and_plane = resolve_surface("(y^2 + z^2 - 0.0025) * (z - 0.8)", so);
  auto tube_per_plane = [&](RadiusAdapt mode) {
    const FloaterSystem sys = settled(tube_and_plane,
                                      {.radius = 0.12,
                                       .max_count = 5000,
                                       .seed = 1,
                                       .radius_adapt = mode,
                                       .snap_to_nodes = false},
                                      300);
    double tube = 0, plane = 0;
    for (const Vec3& p : sys.positions()) (p.z() < 0.5 ? tube : plane) += 1;
    EXPECT_GT(plane, 100);
    return tube / plane;
  };
  const double wh = tube_per_plane(RadiusAdapt::kWitkinHeckbert);
  const double curvature = tube_per_plane(RadiusAdapt::kCurvature);
  RecordProperty("wh", std::to_string(wh));
  RecordProperty("curvature", std::to_string(curvature));
  EXPECT_GT(curvature, 1.2 * wh);
}

// Singularity only (μ_i = β_i): the cone is denser near its node, the apex; Witkin–Heckbert's
// one global fission radius samples it evenly.
TEST(RadiusAdaptModes, SingularOnlyIsDenserNearANode) {
  const Surface cone = catalog_surface("cone");
  auto ratio = [&](RadiusAdapt mode) {
    return cone_apex_ratio(settled(
        cone, {.max_count = 1500, .seed = 10, .radius_adapt = mode, .snap_to_nodes = false}, 300));
  };
  const double wh = ratio(RadiusAdapt::kWitkinHeckbert), singular = ratio(RadiusAdapt::kSingular);
  RecordProperty("wh", std::to_string(wh));
  RecordProperty("singular", std::to_string(singular));
  EXPECT_LT(wh, 1.4);
  EXPECT_GT(wh, 0.6);
  EXPECT_GT(singular, 1.8);
}

}  // namespace
}  // namespace zeroset
