#include "zeroset/floaters/settings.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "zeroset/error.h"
#include "zeroset/io/memory.h"
#include "zeroset/surface/json_read.h"

namespace zeroset {
namespace {

using nlohmann::json;

using json_read::boolean;
using json_read::fail;
using json_read::number;
using json_read::whole;

void check(bool ok, const char* key, const std::string& value, const std::string& why) {
  if (!ok) throw SettingError(key, value, why);
}

}  // namespace

void validate_settings(const FloaterOptions& o) {
  check(o.radius >= 0 && o.radius <= kMaxFloaterRadius, "radius", fmt::format("{}", o.radius),
        fmt::format("must be a length in [0, {:g}] (0: chosen from the surface's area)",
                    kMaxFloaterRadius));
  check(o.max_count >= 1 && o.max_count <= kMaxFloaterCount, "max_count",
        std::to_string(o.max_count), fmt::format("must lie in [1, {}]", kMaxFloaterCount));
  check(o.seed_count <= kMaxFloaterCount, "seed_count", std::to_string(o.seed_count),
        fmt::format("must lie in [0, {}] (0: min(max_count, 200))", kMaxFloaterCount));
  check(o.seed <= kMaxFloaterSeed, "seed", std::to_string(o.seed),
        fmt::format("must lie in [0, {}]", kMaxFloaterSeed));
  check(o.radius_grading >= 0 && o.radius_grading <= kMaxRadiusGrading, "radius_grading",
        fmt::format("{}", o.radius_grading),
        fmt::format("must lie in [0, {:g}] (0: off)", kMaxRadiusGrading));
  // The dynamics' constants (library options, but feedback, equilibrium_speed and
  // estimator_interval, which the command line and scene files set too).
  auto finite = [](double v) { return std::isfinite(v); };
  auto num = [](double v) { return fmt::format("{}", v); };
  check(finite(o.dt) && o.dt > 0, "dt", num(o.dt), "must be positive");
  check(finite(o.repulsion) && o.repulsion > 0, "repulsion", num(o.repulsion), "must be positive");
  check(finite(o.desired_energy_factor) && o.desired_energy_factor > 0, "desired_energy_factor",
        num(o.desired_energy_factor), "must be positive");
  check(finite(o.radius_rate) && o.radius_rate >= 0, "radius_rate", num(o.radius_rate),
        "must not be negative");
  check(finite(o.radius_damping) && o.radius_damping > 0, "radius_damping", num(o.radius_damping),
        "must be positive");
  // The pull's Euler step shrinks the distance to F = 0 by (1 − φ·dt): it diverges from
  // φ·dt = 2 on.
  check(finite(o.feedback) && o.feedback >= 0 && o.feedback * o.dt < kMaxFeedbackStep, "feedback",
        num(o.feedback),
        fmt::format("must lie in [0, {:g}) (feedback·dt below {:g}: the pull's Euler step is "
                    "stable)",
                    kMaxFeedbackStep / o.dt, kMaxFeedbackStep));
  check(finite(o.max_step_fraction) && o.max_step_fraction > 0, "max_step_fraction",
        num(o.max_step_fraction), "must be positive");
  // A tangential move is at most max_step_fraction·σ per step: a γ beyond max_step_fraction/dt
  // counts every floater as near equilibrium; γ = 0 none, and nothing would ever fission.
  const double most_speed = o.max_step_fraction / o.dt;
  check(finite(o.equilibrium_speed) && o.equilibrium_speed > 0 && o.equilibrium_speed <= most_speed,
        "equilibrium_speed", num(o.equilibrium_speed),
        fmt::format("must lie in (0, {:g}] (max_step_fraction/dt: above it every floater counts "
                    "as near equilibrium)",
                    most_speed));
  check(finite(o.fission_energy_factor) && o.fission_energy_factor >= 0, "fission_energy_factor",
        num(o.fission_energy_factor), "must not be negative");
  check(finite(o.death_radius_factor) && o.death_radius_factor >= 0 && o.death_radius_factor < 1,
        "death_radius_factor", num(o.death_radius_factor), "must be in [0, 1)");
  check(finite(o.max_radius_factor) && o.max_radius_factor >= 1, "max_radius_factor",
        num(o.max_radius_factor), "must be at least 1");
  check(o.estimator_interval >= 1 && o.estimator_interval <= kMaxEstimatorInterval,
        "estimator_interval", std::to_string(o.estimator_interval),
        fmt::format("must lie in [1, {}]", kMaxEstimatorInterval));
  check(o.curvature_samples >= 1 && o.curvature_samples <= 64, "curvature_samples",
        std::to_string(o.curvature_samples), "must be between 1 and 64");
  check(finite(o.singular_scale) && o.singular_scale >= 0, "singular_scale", num(o.singular_scale),
        "must be a positive length (or 0 for scene_radius/3)");
  check(finite(o.min_radius_factor) && o.min_radius_factor > 0 && o.min_radius_factor <= 1,
        "min_radius_factor", num(o.min_radius_factor), "must be in (0, 1]");
  check(o.converge_window >= 1, "converge_window", std::to_string(o.converge_window),
        "must be at least 1");
  check(finite(o.converge_churn) && o.converge_churn >= 0, "converge_churn", num(o.converge_churn),
        "must not be negative");
  check(finite(o.converge_speed) && o.converge_speed >= 0, "converge_speed", num(o.converge_speed),
        "must not be negative");
  check(o.threads >= 0, "threads", std::to_string(o.threads), "must not be negative");
}

namespace {

// Reads the entries of a "floaters" object into `o` and validates the result: the one reader of
// floater settings, behind scene files, flags and keywords alike. SettingError names the key.
void read_floater_object(const json& floaters, FloaterOptions& o) {
  using json_read::setting_boolean;
  using json_read::setting_number;
  using json_read::setting_whole;
  // The types here; the ranges are validate_settings' (the same for every entry point).
  const double most = 1e19;  // any whole number a std::uint64_t holds
  for (const auto& [key, value] : floaters.items()) {
    if (key == "max_count")
      o.max_count = setting_whole(value, key, 0, most);
    else if (key == "seed_count")
      o.seed_count = setting_whole(value, key, 0, most);
    else if (key == "seed")
      o.seed = setting_whole(value, key, 0, most);
    else if (key == "radius")
      o.radius = setting_number(value, key);
    else if (key == "radius_grading")
      o.radius_grading = setting_number(value, key);
    else if (key == "feedback")
      o.feedback = setting_number(value, key);
    else if (key == "equilibrium_speed")
      o.equilibrium_speed = setting_number(value, key);
    else if (key == "estimator_interval")
      o.estimator_interval = static_cast<int>(setting_whole(value, key, 0, 1e9));
    else if (key == "cos_weight")
      o.cos_weight = setting_boolean(value, key);
    else if (key == "clip_projection")
      o.clip_projection = setting_boolean(value, key);
    else if (key == "snap_to_nodes")
      o.snap_to_nodes = setting_boolean(value, key);
    else if (key == "scaled_repulsion")
      o.scaled_repulsion = setting_boolean(value, key);
    else if (key == "clip_newton")
      o.clip_newton = setting_boolean(value, key);
    else if (key == "average_radius_factor")
      o.average_radius_factor = setting_boolean(value, key);
    else if (key == "local_nominal_radius")
      o.local_nominal_radius = setting_boolean(value, key);
    else if (key == "energy_taper")
      o.energy_taper = setting_boolean(value, key);
    else if (key == "fission_offset")
      o.fission_offset = setting_boolean(value, key);
    else if (key == "radius_adapt") {
      const std::string text = json_read::setting_string(value, key);
      try {
        o.radius_adapt = parse_radius_adapt(text, key);
      } catch (const InvalidArgument&) {
        throw SettingError(key, text, "expected wh, curvature, singular or mixed");
      }
    } else {
      throw SettingError(
          key, value.dump(),
          "unknown key (known: max_count, seed_count, seed, radius, radius_grading, feedback, "
          "equilibrium_speed, estimator_interval, cos_weight, clip_projection, snap_to_nodes, "
          "scaled_repulsion, clip_newton, average_radius_factor, local_nominal_radius, "
          "energy_taper, fission_offset, radius_adapt)");
    }
  }
  validate_settings(o);
}

}  // namespace

void apply_floater_settings(const json& floaters, FloaterOptions& options,
                            const std::string& origin) {
  const std::string base = "/floaters";
  if (!floaters.is_object()) fail(origin, base, "expected an object");
  FloaterOptions o = options;
  try {
    read_floater_object(floaters, o);
  } catch (const SettingError& e) {
    fail(origin, base + "/" + json_read::pointer_token(e.key()), e.why());
  }
  options = o;
}

void apply_floater_options(const json& given, FloaterOptions& options) {
  FloaterOptions o = options;
  read_floater_object(given, o);
  options = o;
}

json floater_settings_to_json(const FloaterOptions& o) {
  return {{"max_count", o.max_count},
          {"seed_count", o.seed_count},
          {"seed", o.seed},
          {"radius", o.radius},
          {"radius_grading", o.radius_grading},
          {"feedback", o.feedback},
          {"equilibrium_speed", o.equilibrium_speed},
          {"estimator_interval", o.estimator_interval},
          {"cos_weight", o.cos_weight},
          {"clip_projection", o.clip_projection},
          {"snap_to_nodes", o.snap_to_nodes},
          {"scaled_repulsion", o.scaled_repulsion},
          {"clip_newton", o.clip_newton},
          {"average_radius_factor", o.average_radius_factor},
          {"local_nominal_radius", o.local_nominal_radius},
          {"energy_taper", o.energy_taper},
          {"fission_offset", o.fission_offset},
          {"radius_adapt", std::string(to_string(o.radius_adapt))}};
}

void check_floater_memory(const FloaterOptions& options, const std::string& option) {
  const MemoryLimit have = available_memory();
  if (!have.known) return;
  const std::size_t count = std::max(options.max_count, options.seed_count);
  const double needed = static_cast<double>(count) * kBytesPerFloater;
  if (needed <= have.budget()) return;
  const auto fits = static_cast<long long>(have.budget() / kBytesPerFloater);
  throw InvalidArgument(option, std::to_string(count),
                        fmt::format("{} floaters {}; use {} {} or less", count,
                                    memory_shortfall(needed, have), option, fits));
}

}  // namespace zeroset
