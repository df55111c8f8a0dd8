// The public FloaterSystem: options, one step in order, and the state's accessors. The parts of
// a step live in the files named in floater_state_detail.h.
#include "zeroset/floaters/floaters.h"

#include <fmt/core.h>

#include <chrono>
#include <cmath>
#include <numeric>

#include "floater_state_detail.h"
#include "zeroset/error.h"
#include "zeroset/floaters/settings.h"

namespace zeroset {

RadiusAdapt parse_radius_adapt(std::string_view text, std::string_view flag) {
  for (RadiusAdapt m : {RadiusAdapt::kWitkinHeckbert, RadiusAdapt::kCurvature,
                        RadiusAdapt::kSingular, RadiusAdapt::kMixed})
    if (text == to_string(m)) return m;
  throw InvalidArgument(std::string(flag), std::string(text),
                        "expected wh, curvature, singular or mixed");
}

std::string_view to_string(RadiusAdapt mode) {
  switch (mode) {
    case RadiusAdapt::kWitkinHeckbert:
      return "wh";
    case RadiusAdapt::kCurvature:
      return "curvature";
    case RadiusAdapt::kSingular:
      return "singular";
    case RadiusAdapt::kMixed:
      return "mixed";
  }
  return "mixed";
}

namespace detail {
namespace {

StepStats advance(FloaterState& sys, std::span<const double> next_q) {
  const auto t0 = std::chrono::steady_clock::now();
  StepStats st;
  ensure_evaluators(sys);
  if (floater_count(sys) == 0) {
    st.inserted = insert_random(sys, initial_count(sys));
    evaluate_all(sys);
  }
  if (sys.opt.radius_adapt == RadiusAdapt::kWitkinHeckbert)
    std::fill(sys.mu.begin(), sys.mu.end(), 1.0);
  std::size_t held_removed = 0;
  if (sys.step_count % static_cast<std::size_t>(sys.opt.estimator_interval) == 0) {
    const SingularEvents held = keep_singular_floaters(sys);
    st.inserted += held.inserted;
    held_removed = held.removed;
    if (held.inserted + held.removed > 0) evaluate_all(sys);  // F and ∇F of the new floaters
    update_estimators(sys);
  }

  std::vector<double> qdot;
  if (!next_q.empty()) {
    const auto q = sys.surface.field.parameter_values();
    for (std::size_t k = 0; k < q.size(); ++k) qdot.push_back((next_q[k] - q[k]) / sys.opt.dt);
  }
  build_neighbours(sys);
  chain_velocities(sys);
  parameter_terms(sys, qdot);
  repulsion_and_move(sys);

  // Summed in chunk order: the same on any number of threads.
  double sq = 0;
  for (double v : sys.chunk_speed) sq += v;
  st.rms_speed =
      floater_count(sys) > 0 ? std::sqrt(sq / static_cast<double>(floater_count(sys))) : 0;
  st.near_equilibrium =
      std::accumulate(sys.chunk_near.begin(), sys.chunk_near.end(), std::size_t{0});

  // Fates are judged on this step's motion and energies, at the moved positions.
  sys.pos.swap(sys.new_pos);
  sys.sigma.swap(sys.new_sigma);
  const FateCounts fates = decide_fates(sys);
  if (!next_q.empty()) {
    held_removed += drop_singular_set(sys);
    apply_parameters(sys, next_q);
    track_nodes(sys);
  } else {
    ++sys.still_steps;
  }
  evaluate_all(sys);
  // No floater stays where F or ∇F is not finite (it moved onto a pole or into a NaN region)
  // or outside the clip: what a step leaves is always defined and inside.
  st.undefined_removed = remove_undefined(sys);

  ++sys.step_count;
  st.step = sys.step_count;
  st.births = fates.births;
  st.deaths = fates.deaths;
  st.removed = fates.removed + held_removed + st.undefined_removed;
  st.count = floater_count(sys);
  st.converged = judge_convergence(sys, st);
  residual_stats(sys, st);
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return st;
}

// The floaters stay where they are, but nothing else of the old surface carries over: ages
// (for stray detection), fission radii, nodes held, and the convergence history.
void restart_on_new_surface(FloaterState& sys) {
  sys.still_steps = 0;
  for (std::size_t i = 0; i < floater_count(sys); ++i) {
    sys.pos[i] = sys.surface.clip.project(sys.pos[i]);
    sys.sigma[i] = sys.sigma_hat;
    sys.age[i] = 0;
    sys.pinned[i] = 0;
    sys.mu[i] = 1;
    sys.smax[i] = sigma_max(sys);
  }
  sys.recent.clear();
  evaluate_all(sys);
}

void reset_floaters(FloaterState& sys) {
  resize_state(sys, 0);
  sys.singular_placed = false;
  sys.next_id = 0;
  sys.step_count = 0;
  sys.recent.clear();
  insert_random(sys, initial_count(sys));
  evaluate_all(sys);
}

void set_options(FloaterState& sys, const FloaterOptions& o) {
  validate_settings(o);
  const bool lengths = o.radius != sys.opt.radius || o.singular_scale != sys.opt.singular_scale ||
                       (o.radius == 0 && o.max_count != sys.opt.max_count);
  sys.opt = o;
  if (lengths) resolve_lengths(sys);
  // The held floaters' radius and spacing follow σ̂, the cap and the radius rule.
  replace_singular_floaters(sys);
  if (floater_count(sys) > sys.opt.max_count) resize_state(sys, sys.opt.max_count);
  if (sys.opt.radius_adapt == RadiusAdapt::kWitkinHeckbert)
    std::fill(sys.mu.begin(), sys.mu.end(), 1.0);
  ensure_evaluators(sys);
  sys.shown_normals_valid = false;
}

const std::vector<Vec3>& drawn_normals(const FloaterState& sys) {
  if (!sys.shown_normals_valid) {
    sys.shown_normals.resize(floater_count(sys));
    for (std::size_t i = 0; i < floater_count(sys); ++i)
      sys.shown_normals[i] = sys.unit[i].squaredNorm() > 0 ? sys.unit[i] : Vec3(Vec3::UnitZ());
    sys.shown_normals_valid = true;
  }
  return sys.shown_normals;
}

}  // namespace
}  // namespace detail

// The system is its plain state; the parts of a step are free functions on it.
struct FloaterSystem::Impl : detail::FloaterState {
  Impl(const Surface& s, const FloaterOptions& o, std::stop_token st) {
    validate_settings(o);
    opt = o;
    stop = std::move(st);
    detail::adopt_surface(*this, s);
    detail::insert_random(*this, detail::initial_count(*this));
    detail::evaluate_all(*this);
  }
};

FloaterSystem::FloaterSystem(const Surface& surface, const FloaterOptions& options,
                             std::stop_token stop)
    : impl_(std::make_unique<Impl>(surface, options, std::move(stop))) {}
FloaterSystem::~FloaterSystem() = default;
FloaterSystem::FloaterSystem(FloaterSystem&&) noexcept = default;
FloaterSystem& FloaterSystem::operator=(FloaterSystem&&) noexcept = default;

StepStats FloaterSystem::step() { return detail::advance(*impl_, {}); }

StepStats FloaterSystem::step(std::span<const double> next_parameters) {
  detail::check_parameters(*impl_, next_parameters);
  return detail::advance(*impl_, next_parameters);
}

void FloaterSystem::set_parameters(std::span<const double> values) {
  detail::check_parameters(*impl_, values);
  detail::drop_singular_set(*impl_);
  detail::apply_parameters(*impl_, values);
  detail::track_nodes(*impl_);
  detail::evaluate_all(*impl_);
}

void FloaterSystem::set_parameter(std::string_view name, double value) {
  const int k = impl_->surface.field.parameter_index(name);
  if (k < 0)
    throw InvalidArgument(std::string(name), fmt::format("{}", value),
                          fmt::format("{} has no such parameter", impl_->surface.label()));
  std::vector<double> q = impl_->surface.field.parameter_values();
  q[static_cast<std::size_t>(k)] = value;
  set_parameters(q);
}

std::span<const double> FloaterSystem::parameters() const {
  return impl_->surface.field.parameter_values();
}

void FloaterSystem::set_surface(const Surface& surface) {
  detail::drop_singular_set(*impl_);
  detail::adopt_surface(*impl_, surface);
  detail::restart_on_new_surface(*impl_);
}

const Surface& FloaterSystem::surface() const { return impl_->surface; }

void FloaterSystem::set_options(const FloaterOptions& options) {
  detail::set_options(*impl_, options);
}
const FloaterOptions& FloaterSystem::options() const { return impl_->opt; }

void FloaterSystem::reset() { detail::reset_floaters(*impl_); }

void FloaterSystem::reseed(std::uint64_t seed) {
  impl_->opt.seed = seed;
  detail::reset_floaters(*impl_);
}

double FloaterSystem::nominal_radius() const { return impl_->sigma_hat; }
std::size_t FloaterSystem::size() const { return detail::floater_count(*impl_); }
std::size_t FloaterSystem::steps_taken() const { return impl_->step_count; }
std::span<const Vec3> FloaterSystem::positions() const { return impl_->pos; }
std::span<const double> FloaterSystem::radii() const { return impl_->sigma; }
std::span<const Vec3> FloaterSystem::normals() const { return detail::drawn_normals(*impl_); }
std::span<const std::uint64_t> FloaterSystem::ids() const { return impl_->id; }
std::span<const double> FloaterSystem::max_radii() const { return impl_->smax; }

}  // namespace zeroset
