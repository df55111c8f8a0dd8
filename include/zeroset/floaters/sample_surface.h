#pragma once
/// The floater recipe, one for every front end (docs/algorithms.md, B; docs/python.md): survey
/// the field, seed a FloaterSystem, step it until it settles (or a given number of steps), or
/// settle it at the start value of a parameter and then move that parameter linearly, and
/// measure the result. `zeroset sample` and Python's Surface.sample call sample_surface();
/// its statistics serialise through SampleResult::to_json(), the `--stats` file of
/// `zeroset sample` and the dictionary Python returns.
#include <cstddef>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "zeroset/floaters/floaters.h"
#include "zeroset/floaters/metrics.h"
#include "zeroset/surface/field_survey.h"
#include "zeroset/surface/singular_set.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

/// A parameter moving linearly from `from` to `to` over `steps` steps (q̇ known to the F_q·q̇
/// term), after at most `settle_steps` steps at `from` (random seeding is far from F = 0).
struct SampleAnimation {
  std::string parameter;
  double from = 0;
  double to = 0;
  std::size_t steps = 0;
  std::size_t settle_steps = 1000;
};

/// How long the floaters run and what is measured.
struct SampleRun {
  /// Exactly this many steps; none: until settled, at most max_steps. Ignored with animation.
  std::optional<std::size_t> steps;
  std::size_t max_steps = 3000;
  std::optional<SampleAnimation> animation;
  bool survey = true;  ///< survey the field first (FieldSurvey and its warning)
  /// Measure the point set (SampleMetrics) and its coverage of the singular set; band 0 in
  /// the options: half the nominal radius σ̂.
  std::optional<MetricsOptions> metrics;
  /// Find the singular set of the final parameters also without metrics (for an overlay).
  bool singular_set = false;
  /// Each warning as it arises (kept in SampleResult::warnings too).
  std::function<void(const std::string&)> on_warning;
  /// After each step: its figures and the fraction of the run done (the settling of an
  /// animation not counted: 0 until it is over).
  std::function<void(const StepStats&, double done)> on_step;
};

/// Figures of an animation.
struct SampleAnimationStats {
  std::size_t settle_steps = 0;  ///< steps the settling took
  double median_residual_worst = 0;
  double max_residual_worst = 0;
  std::size_t count_min = 0;
  std::size_t count_max = 0;
};

/// The floaters with everything measured on the way.
struct SampleResult {
  /// The floaters; none when F vanishes identically (there is no surface to sample).
  std::optional<FloaterSystem> system;
  Surface surface;  ///< at the final parameter values
  SampleRun run;    ///< as run (without its callbacks)
  std::optional<FieldSurvey> survey;
  StepStats last;                           ///< the last step's figures
  double seconds = 0;                       ///< over the steps
  std::size_t updates = 0;                  ///< floater updates over the steps
  std::size_t undefined_removed = 0;        ///< floaters removed where F or ∇F was not finite
  std::optional<std::size_t> converged_at;  ///< the step at which the system first settled
  std::optional<SampleAnimationStats> animation;
  std::optional<SampleMetrics> metrics;
  double band = 0;  ///< the band's half width the metrics used
  std::optional<SingularSet> singular;
  std::optional<SingularSetCoverage> coverage;
  std::vector<std::string> warnings;
  bool stopped = false;  ///< the stop token ended it early

  /// The stats file of `zeroset sample --stats` (docs/algorithms.md, B.7).
  nlohmann::json to_json() const;
};

/// Samples `surface` with floaters. `options` are validated by the FloaterSystem. Throws
/// InvalidArgument for an animation of a parameter the surface does not have, or without
/// steps. When `stop` is requested the run returns early with `stopped` set.
SampleResult sample_surface(const Surface& surface, const FloaterOptions& options,
                            const SampleRun& run = {}, std::stop_token stop = {});

}  // namespace zeroset
