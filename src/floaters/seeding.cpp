// Set-up of a floater system on a surface (lengths, evaluators, parameters) and random seeding.
#include "floater_state_detail.h"

#include <fmt/core.h>

#include "zeroset/error.h"
#include "zeroset/floaters/metrics.h"

namespace zeroset::detail {

std::size_t initial_count(const FloaterState& sys) {
  const std::size_t wanted = sys.opt.seed_count > 0 ? sys.opt.seed_count : 200;
  return std::min(wanted, sys.opt.max_count);
}

void adopt_surface(FloaterState& sys, const Surface& s) {
  s.field.require_parameters();
  sys.box = s.bounds();  // throws BadInput for an unbounded clip
  sys.surface = s;
  sys.scene_radius = sys.surface.scene_radius();
  resolve_lengths(sys);
  sys.evaluators.clear();
  ensure_evaluators(sys);
  find_singular(sys);
}

void resolve_lengths(FloaterState& sys) {
  if (sys.opt.radius > 0) {
    // Beyond these bounds nothing sensible can happen (one floater larger than the scene, or
    // radii whose squares underflow), so σ̂ is kept inside them.
    sys.sigma_hat = std::clamp(sys.opt.radius, kMinNominal * sys.scene_radius, sys.scene_radius);
  } else {
    const double area = estimate_area(sys.surface, 1, sys.stop);
    const double target = std::max<double>(1, static_cast<double>(sys.opt.max_count) / 3);
    sys.sigma_hat = area > 0 ? std::sqrt(area / (kAreaPerFloater * target)) : sys.scene_radius / 10;
    sys.sigma_hat = std::clamp(sys.sigma_hat, 1e-4 * sys.scene_radius, sys.scene_radius);
  }
  sys.singular_scale = sys.opt.singular_scale > 0 ? sys.opt.singular_scale : sys.scene_radius / 3;
}

void ensure_evaluators(FloaterState& sys) {
  sys.threads = worker_count(sys.opt.threads);
  while (static_cast<int>(sys.evaluators.size()) < sys.threads)
    sys.evaluators.emplace_back(sys.surface.field);
  sys.perimeter.resize(sys.evaluators.size());
  sys.hessian_batch.resize(sys.evaluators.size());
}

namespace {

Vec3 random_point_in_clip(const FloaterState& sys, Rng& rng) {
  Vec3 p = sys.box.center();
  for (int attempt = 0; attempt < 64; ++attempt) {
    for (int k = 0; k < 3; ++k) p[k] = rng.uniform(sys.box.lo[k], sys.box.hi[k]);
    if (sys.surface.clip.contains(p)) return p;
  }
  return sys.surface.clip.project(p);  // a sliver of a clip volume: its boundary will do
}

}  // namespace

std::size_t insert_random(FloaterState& sys, std::size_t count) {
  count = std::min(count, sys.opt.max_count - std::min(sys.opt.max_count, floater_count(sys)));
  for (std::size_t k = 0; k < count; ++k) {
    Rng rng(sys.opt.seed, sys.next_id, 0, Stream::kInsert);
    push_floater(sys, random_point_in_clip(sys, rng), sys.sigma_hat, 1.0);
  }
  sys.shown_normals_valid = false;
  return count;
}

void apply_parameters(FloaterState& sys, std::span<const double> q) {
  for (std::size_t k = 0; k < q.size(); ++k) {
    sys.surface.field.set_parameter(static_cast<int>(k), q[k]);
    for (Evaluator& ev : sys.evaluators) ev.set_parameter(static_cast<int>(k), q[k]);
  }
  if (sys.surface.clip.is_parametric()) {  // the clip follows the parameters (checked before)
    sys.surface.clip.update(sys.surface.field);
    sys.box = sys.surface.bounds();
    sys.scene_radius = sys.surface.scene_radius();
  }
}

void check_parameters(const FloaterState& sys, std::span<const double> q) {
  const std::size_t want = sys.surface.field.parameter_names().size();
  if (q.size() != want)
    throw InvalidArgument(fmt::format("expected {} parameter values for {}, got {}", want,
                                      sys.surface.label(), q.size()));
  for (std::size_t k = 0; k < q.size(); ++k)
    if (!std::isfinite(q[k]))
      throw InvalidArgument(sys.surface.field.parameter_names()[k], fmt::format("{}", q[k]),
                            "a parameter must be finite");
  if (sys.surface.clip.is_parametric()) {  // refused before anything changes
    Field f = sys.surface.field;
    for (std::size_t k = 0; k < q.size(); ++k) f.set_parameter(static_cast<int>(k), q[k]);
    Clip c = sys.surface.clip;
    c.update(f);
    if (!c.is_bounded()) throw BadInput("the clip volume is unbounded at these parameters");
  }
}

}  // namespace zeroset::detail
