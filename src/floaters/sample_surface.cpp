// The floater recipe of every front end (zeroset/floaters/sample_surface.h): survey, seed,
// settle or animate, measure.
#include "zeroset/floaters/sample_surface.h"

#include <fmt/core.h>

#include <algorithm>
#include <utility>

#include "zeroset/error.h"

namespace zeroset {
namespace {

void say_warning(SampleResult& r, const SampleRun& run, std::string line) {
  if (run.on_warning) run.on_warning(line);
  r.warnings.push_back(std::move(line));
}

// Counts one step into the result's totals.
const StepStats& count_step(SampleResult& r, const StepStats& st) {
  r.last = st;
  r.seconds += st.seconds;
  r.updates += st.count;
  r.undefined_removed += st.undefined_removed;
  if (st.converged && !r.converged_at) r.converged_at = st.step;
  return r.last;
}

void report(const SampleRun& run, const StepStats& st, std::size_t done, std::size_t of) {
  if (run.on_step) run.on_step(st, static_cast<double>(done) / static_cast<double>(of));
}

// Unanimated: a fixed number of steps, or until settled.
void settle(SampleResult& r, const SampleRun& run, std::stop_token stop) {
  FloaterSystem& sys = *r.system;
  const std::size_t limit = run.steps.value_or(run.max_steps);
  for (std::size_t k = 0; k < limit && !stop.stop_requested(); ++k) {
    const StepStats& st = count_step(r, sys.step());
    report(run, st, k + 1, limit);
    if (!run.steps && st.converged) break;
  }
}

// Settle at the start value first (random seeding is far from the surface), then move the
// parameter linearly over the animation's steps, q̇ known to the F_q·q̇ term.
void animate(SampleResult& r, const SampleRun& run, int index, std::stop_token stop) {
  const SampleAnimation& a = *run.animation;
  FloaterSystem& sys = *r.system;
  for (std::size_t k = 0; k < a.settle_steps && !stop.stop_requested(); ++k) {
    const StepStats& st = count_step(r, sys.step());
    report(run, st, 0, 1);
    if (st.converged) break;
  }
  SampleAnimationStats& s = r.animation.emplace();
  s.settle_steps = sys.steps_taken();
  s.count_min = s.count_max = sys.size();
  std::vector<double> q(sys.parameters().begin(), sys.parameters().end());
  for (std::size_t k = 1; k <= a.steps && !stop.stop_requested(); ++k) {
    q[static_cast<std::size_t>(index)] =
        a.from + (a.to - a.from) * static_cast<double>(k) / static_cast<double>(a.steps);
    const StepStats& st = count_step(r, sys.step(q));
    s.median_residual_worst = std::max(s.median_residual_worst, st.median_residual);
    s.max_residual_worst = std::max(s.max_residual_worst, st.max_residual);
    s.count_min = std::min(s.count_min, st.count);
    s.count_max = std::max(s.count_max, st.count);
    report(run, st, k, a.steps);
  }
}

// The singular set of the final parameters and the measures of the point set.
void measure(SampleResult& r, const SampleRun& run, std::stop_token stop) {
  const FloaterSystem& sys = *r.system;
  if (run.metrics || run.singular_set) r.singular = find_singular_set_if_bounded(r.surface, stop);
  if (!run.metrics || stop.stop_requested()) return;
  MetricsOptions mo = *run.metrics;
  if (!(mo.band_halfwidth > 0)) mo.band_halfwidth = sys.nominal_radius() / 2;
  r.band = mo.band_halfwidth;
  r.metrics = measure_samples(r.surface, sys.positions(), mo);
  // Each special point's and curve's coverage in local spacings (docs/algorithms.md B.7).
  if (r.singular) r.coverage = measure_singular_coverage(*r.singular, sys.positions());
}

// What a user should hear about the final floaters.
void check_result(SampleResult& r, const SampleRun& run) {
  const FloaterSystem& sys = *r.system;
  // Floaters that find no surface are reseeded, wander, and are removed as strays.
  if (sys.size() == 0)
    say_warning(r, run,
                fmt::format("{}: no floater stayed on the surface; F = 0 may have no point "
                            "inside the clip, or F may be undefined there (try zeroset eval)",
                            r.surface.label()));
  else if (!(r.last.median_residual <= sys.nominal_radius()))
    say_warning(r, run,
                fmt::format("{}: the floaters are not on F = 0 (median |F|/|grad F| {:.3g}, "
                            "sigma^ {:.3g}); the run may be too short (--steps), or F = 0 may "
                            "have no point inside the clip",
                            r.surface.label(), r.last.median_residual, sys.nominal_radius()));
  if (auto line = singular_sheet_warning(r.surface, r.singular ? &*r.singular : nullptr))
    say_warning(r, run, std::move(*line));
}

}  // namespace

SampleResult sample_surface(const Surface& surface, const FloaterOptions& options,
                            const SampleRun& run, std::stop_token stop) {
  SampleResult r;
  r.surface = surface;
  r.run = run;
  r.run.on_warning = nullptr, r.run.on_step = nullptr;
  int index = -1;
  if (run.animation) {
    const SampleAnimation& a = *run.animation;
    index = surface.field.parameter_index(a.parameter);
    if (index < 0)
      throw InvalidArgument("animate", a.parameter,
                            fmt::format("{} has no parameter '{}'", surface.label(), a.parameter));
    if (a.steps == 0)
      throw InvalidArgument("animate", a.parameter, "give the number of animated steps");
    r.surface.field.set_parameter(index, a.from);
    r.surface.clip.update(r.surface.field);
  }
  if (run.survey) {
    r.survey = survey_field(r.surface);
    if (auto line = survey_warning(r.surface, *r.survey)) say_warning(r, run, std::move(*line));
    // Every point is on F = 0 (warned): no floaters, as a mesh gets no triangles.
    if (r.survey->vanishes_identically()) return r;
  }
  FloaterSystem& sys = r.system.emplace(r.surface, options, stop);
  if (options.radius > 0 && sys.nominal_radius() != options.radius)
    say_warning(r, run,
                fmt::format("radius {:g} is outside [1e-9, 1] times the scene radius ({:g}); "
                            "using {:.4g}",
                            options.radius, r.surface.scene_radius(), sys.nominal_radius()));
  if (run.animation)
    animate(r, run, index, stop);
  else
    settle(r, run, stop);
  r.surface = sys.surface();
  measure(r, run, stop);
  r.stopped = stop.stop_requested();
  if (!r.stopped) check_result(r, run);
  return r;
}

}  // namespace zeroset
