// The statistics of a floater run as JSON (SampleResult::to_json): the `--stats` file of
// `zeroset sample` and the dictionary of Python's Surface.sample.
#include <nlohmann/json.hpp>

#include "zeroset/floaters/sample_surface.h"
#include "zeroset/floaters/settings.h"
#include "zeroset/surface/json_read.h"

namespace zeroset {
namespace {

using json = nlohmann::json;

json metrics_json(const SampleMetrics& m, double band) {
  json j;
  j["count"] = m.count;
  j["residual"] = {{"median", m.residual_median},
                   {"max", m.residual_max},
                   {"excluded_near_singular_points", m.residual_excluded}};
  j["spacing"] = {{"mean", m.spacing_mean}, {"cv", m.spacing_cv}};
  j["covering"] = {{"radius", m.covering_radius},
                   {"relative_to_spacing", m.covering_relative},
                   {"reference_points", m.reference_count}};
  json sing = json::array();
  for (const auto& c : m.singular)
    sing.push_back({{"point", json_read::from_vec3(c.point)},
                    {"distance", c.distance},
                    {"local_spacing", c.local_spacing},
                    {"ratio", c.ratio}});
  j["singular_points"] = sing;
  j["singular_ratio_max"] = m.singular_ratio_max;
  j["band"] = {{"halfwidth", band},
               {"density_ratio", m.band_density_ratio},
               {"samples", m.band_samples},
               {"reference_points", m.band_reference}};
  return j;
}

}  // namespace

json SampleResult::to_json() const {
  if (!system)  // F vanishes identically: the survey says so
    return {{"surface", surface.label()}, {"floaters", 0}, {"field", survey_json(*survey)}};
  const FloaterSystem& sys = *system;
  json stats;
  stats["surface"] = surface.label();
  json params = json::object();
  for (std::size_t k = 0; k < surface.field.parameter_names().size(); ++k)
    params[surface.field.parameter_names()[k]] = surface.field.parameter_values()[k];
  stats["parameters"] = params;
  // The options as a scene file's "floaters" object, the radius as chosen.
  json options = floater_settings_to_json(sys.options());
  options["radius_given"] = sys.options().radius;
  options["radius"] = sys.nominal_radius();
  stats["options"] = options;
  const double steps = static_cast<double>(sys.steps_taken());
  stats["steps"] = sys.steps_taken();
  stats["converged_at_step"] = converged_at ? json(*converged_at) : json();
  stats["seconds"] = seconds;
  stats["steps_per_second"] = seconds > 0 ? steps / seconds : 0;
  stats["updates_per_second"] = seconds > 0 ? static_cast<double>(updates) / seconds : 0;
  if (survey) stats["field"] = survey_json(*survey);
  // Floaters removed where F or ∇F was not finite or outside the clip, over the run.
  stats["undefined_removed"] = undefined_removed;
  stats["singular_set"] = singular ? singular_set_json(*singular, false) : json();
  if (metrics) stats["metrics"] = metrics_json(*metrics, band);
  if (coverage)
    stats["singular_coverage"] = {{"point_ratio", coverage->point_ratio},
                                  {"point_ratio_max", coverage->point_ratio_max},
                                  {"curve_gap", coverage->curve_gap},
                                  {"curve_gap_max", coverage->curve_gap_max}};
  if (animation) {
    const SampleAnimation& a = *run.animation;
    stats["animation"] = {{"parameter", a.parameter},
                          {"from", a.from},
                          {"to", a.to},
                          {"steps", a.steps},
                          {"settle_steps", animation->settle_steps},
                          {"median_residual_worst", animation->median_residual_worst},
                          {"max_residual_worst", animation->max_residual_worst},
                          {"count_min", animation->count_min},
                          {"count_max", animation->count_max}};
  }
  return stats;
}

}  // namespace zeroset
