#pragma once
/// The floater settings a user gives, and the "floaters" object of a scene file: the
/// FloaterOptions a scene carries, by field name, read by `zeroset sample` and the viewer and
/// written by the viewer's save-scene.
///
///   "floaters": {"max_count": 2000, "radius": 0, "seed": 1, "seed_count": 200,
///                "cos_weight": true, "clip_projection": true, "snap_to_nodes": true,
///                "scaled_repulsion": true, "radius_grading": 0.1, "radius_adapt": "mixed",
///                "feedback": 15, "equilibrium_speed": 4, "estimator_interval": 8,
///                "clip_newton": true, "average_radius_factor": true,
///                "local_nominal_radius": true, "energy_taper": true, "fission_offset": true}
///
/// Every key is optional; missing ones keep their current value. radius 0 chooses σ̂ from the
/// surface's area. The booleans are FloaterOptions' switches (false: the paper's or
/// Witkin–Heckbert's plain rule, see docs/floaters.md). The command line, scene files and the
/// viewer check these settings with validate_settings below, so each refuses a bad value with
/// the same words.
#include <cstddef>
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "zeroset/floaters/floaters.h"

namespace zeroset {

/// Most floaters (max_count) and most random seeds (seed_count) a run may ask for.
inline constexpr std::size_t kMaxFloaterCount = 100'000'000;
/// Largest random seed: scene files are JSON, whose numbers hold every whole number up to 2^53.
inline constexpr std::uint64_t kMaxFloaterSeed = std::uint64_t{1} << 53;

/// The largest floater radius a user may give: the diameter of the largest clip volume
/// (kMaxClipCoordinate); the run keeps the radius within the scene radius anyway.
inline constexpr double kMaxFloaterRadius = 2e6;
/// The largest radius grading (the growth of the fission radius per neighbour distance; 0.1
/// by default): beyond a few units it no longer limits anything.
inline constexpr double kMaxRadiusGrading = 1000;
/// feedback·dt stays below this: the pull towards F = 0 multiplies the distance by
/// (1 − feedback·dt) per step, which diverges from 2 on.
inline constexpr double kMaxFeedbackStep = 2;
/// The longest estimator interval: beyond it μ_i would hardly ever be refreshed in a run.
inline constexpr int kMaxEstimatorInterval = 1000;

/// Checks the settings a user gives: radius in [0, kMaxFloaterRadius] (0: chosen from the
/// surface's area), max_count in [1, kMaxFloaterCount], seed_count in [0, kMaxFloaterCount],
/// seed in [0, kMaxFloaterSeed], radius_grading in [0, kMaxRadiusGrading], feedback in
/// [0, kMaxFeedbackStep/dt), equilibrium_speed in (0, max_step_fraction/dt], estimator_interval
/// in [1, kMaxEstimatorInterval]; and the dynamics' constants that only the library sets (dt,
/// repulsion, the estimators' and convergence settings).
/// The one check of FloaterOptions: FloaterSystem runs it too. Throws SettingError naming the key
/// as the scene file does.
void validate_settings(const FloaterOptions& options);

/// Applies `floaters` (the object above) to `options`, then validates them. Throws BadInput
/// naming `origin` and the JSON pointer of a malformed or refused entry (e.g. "scene.json:
/// /floaters/max_count: must lie in [1, 100000000]"). Unknown keys are an error too, so typos
/// do not pass silently.
void apply_floater_settings(const nlohmann::json& floaters, FloaterOptions& options,
                            const std::string& origin);

/// Applies the options a user gave, only those given, as an object with the keys above (a
/// front end's flags or keywords: {"max_count": 500, "cos_weight": false}), then validates:
/// the one way from a front end's options into the settings. Throws SettingError naming the
/// key, for a value of the wrong type or outside its rule, or an unknown key.
void apply_floater_options(const nlohmann::json& given, FloaterOptions& options);

/// The "floaters" object for `options`.
nlohmann::json floater_settings_to_json(const FloaterOptions& options);

/// Memory one floater takes in a run, all its state and outputs included (measured: about
/// 550 bytes at 10^6 floaters).
inline constexpr double kBytesPerFloater = 600;

/// Refuses options whose population (the larger of max_count and seed_count) would not fit in
/// the memory this process may still take (available_memory in zeroset/io/memory.h): throws
/// InvalidArgument naming `option` (what the front end calls max_count), the limit that
/// applies and the largest count that fits. For front ends, before a long run.
void check_floater_memory(const FloaterOptions& options, const std::string& option);

}  // namespace zeroset
