#include "zeroset/surface/field_survey.h"

#include <fmt/format.h>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <vector>

#include "zeroset/error.h"
#include "zeroset/expr/field.h"

namespace zeroset {

FieldSurvey survey_field(const Surface& surface, int nodes) {
  if (nodes < 2) throw InvalidArgument("survey_field: nodes must be at least 2");
  FieldSurvey s;
  if (!surface.clip.is_bounded()) return s;
  surface.field.require_parameters();
  const Box3 box = surface.clip.bounds();
  const Vec3 size = box.hi - box.lo;
  const double h = size.maxCoeff() / (nodes - 1);
  if (!(h > 0) || !std::isfinite(h)) return s;
  long long n[3];
  for (int a = 0; a < 3; ++a) n[a] = std::max<long long>(1, std::llround(size[a] / h) + 1);
  // The nodes inside the clip through the field's batched evaluation, a few thousand at a
  // time: the batches stay in the cache (the whole grid would be megabytes of fresh pages).
  constexpr size_t kBatch = 4096;
  std::vector<double> x, y, z, f;
  x.reserve(kBatch), y.reserve(kBatch), z.reserve(kBatch);
  Evaluator eval(surface.field);
  auto flush = [&] {
    if (x.empty()) return;
    f.resize(x.size());
    eval.values(x, y, z, f);
    for (double v : f) {
      ++s.samples;
      if (!std::isfinite(v))
        ++s.undefined;
      else if (v == 0)
        ++s.zero;
    }
    x.clear(), y.clear(), z.clear();
  };
  auto add = [&](const Vec3& p) {
    if (!surface.clip.contains(p)) return;
    x.push_back(p.x()), y.push_back(p.y()), z.push_back(p.z());
    if (x.size() == kBatch) flush();
  };
  for (long long k = 0; k < n[2]; ++k)
    for (long long j = 0; j < n[1]; ++j)
      for (long long i = 0; i < n[0]; ++i)
        add(box.lo +
            h * Vec3(static_cast<double>(i), static_cast<double>(j), static_cast<double>(k)));
  if (x.empty()) add(0.5 * (box.lo + box.hi));  // a clip smaller than the grid's spacing
  flush();
  return s;
}

std::optional<std::string> survey_warning(const Surface& surface, const FieldSurvey& survey) {
  if (survey.vanishes_identically())
    return fmt::format(
        "{}: F vanishes identically on the clip (F = 0 everywhere): there is no "
        "surface to find",
        surface.label());
  if (survey.undefined == 0) return std::nullopt;
  const double percent = 100 * survey.undefined_fraction();
  return fmt::format(
      "{}: F is undefined (NaN or infinite) on {} of the clip; those parts are "
      "left out",
      surface.label(),
      percent >= 0.1 ? fmt::format("{:.1f}%", percent) : std::string("less than 0.1%"));
}

nlohmann::json survey_json(const FieldSurvey& survey) {
  return {{"samples", survey.samples},
          {"undefined_samples", survey.undefined},
          {"undefined_fraction", survey.undefined_fraction()},
          {"vanishes_identically", survey.vanishes_identically()}};
}

}  // namespace zeroset
