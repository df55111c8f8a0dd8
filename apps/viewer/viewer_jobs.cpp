// The viewer's frame loop and background jobs: the ray-traced preview, the live floater
// simulation and the mesh with its improver steps, restarted when what they show changed.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <thread>

#include <fmt/core.h>

#include "viewer_state.h"
#include "viewer_state_detail.h"
#include "zeroset/mesh/carry.h"
#include "zeroset/mesh/mesh_ops.h"
#include "zeroset/mesh/mesh_surface.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset::viewer {
namespace {

using json = nlohmann::json;

// A parameter jump larger than this fraction of its range is applied at once (floaters
// re-settle through the φF term) rather than through the F_q·q̇ term, which is a first-order
// prediction and overshoots for large steps.
constexpr double kGlideFraction = 0.05;

// A carried mesh is improved further only when no new parameter value came for this long.
constexpr auto kCarriedRestDelay = std::chrono::milliseconds(250);

// Frame rate estimate smoothing (exponential, per frame).
constexpr double kFpsSmoothing = 0.1;

// Measures the simulation rate over windows of about half a second.
class RateMeter {
 public:
  double tick() {
    const auto now = std::chrono::steady_clock::now();
    ++count_;
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    if (elapsed >= 0.5) {
      rate_ = count_ / elapsed;
      count_ = 0;
      start_ = now;
    }
    // Until the first half second has passed, the rate so far.
    return rate_ > 0 || elapsed <= 0 ? rate_ : count_ / elapsed;
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  int count_ = 0;
  double rate_ = 0;
};

}  // namespace

json ViewerStats::to_json() const {
  json j = {{"mode", std::string(viewer::to_string(mode))},
            {"fps", fps},
            {"draw_ms", 1000 * draw_seconds},
            {"busy", is_busy}};
  switch (mode) {
    case Mode::kFloaters:
      j["floaters"] = {{"count", floater_count},
                       {"steps", floater_steps},
                       {"steps_per_second", steps_per_second},
                       {"median_residual", median_residual},
                       {"max_residual", max_residual},
                       {"nominal_radius", nominal_radius},
                       {"converged", converged}};
      break;
    case Mode::kMesh:
      j["mesh"] = {{"vertices", mesh_vertices},
                   {"triangles", mesh_triangles},
                   {"improver_steps", improver_steps},
                   {"polygonize_seconds", polygonize_seconds},
                   {"updates_per_second", mesh_updates_per_second},
                   {"carried", mesh_carried},
                   {"rebuilt", mesh_rebuilt},
                   {"last_update", mesh_update}};
      break;
    case Mode::kRaytrace:
      j["raytrace"] = {{"divisor", preview_divisor}, {"seconds", preview_seconds}};
      break;
  }
  if (show_singular) j["singular"] = detail::singular_json(singular.get(), singular_is_current);
  return j;
}

// ---- frames and jobs ---------------------------------------------------------------------------

bool ViewerState::update(double now_s) {
  const double dt = last_update_s_ < 0 ? 0 : std::clamp(now_s - last_update_s_, 0.0, 0.1);
  last_update_s_ = now_s;
  // A moving parameter shows through the results it leads to (new pictures, floaters that
  // follow it); only the end of an animation is news in itself.
  const bool was_playing = animation_.is_playing;
  advance_animation(dt);
  bool is_new = was_playing != animation_.is_playing;
  floater_control_->is_animating = animation_.is_playing;
  is_new |= collect_results(now_s);
  if (auto error = worker_.take_error()) {
    set_status(*error, true);
    is_new = true;
  }
  is_new |= update_singular();
  survey_if_due(now_s);
  restart_if_needed();
  return is_new;
}

void ViewerState::set_live_frame_interval(double seconds) {
  live_frame_interval_s_ = std::clamp(seconds, kMinLiveFrameInterval, kMaxLiveFrameInterval);
}

void ViewerState::frame_drawn(double now_s, double seconds) {
  draw_seconds_ = seconds;
  if (last_frame_s_ >= 0 && now_s > last_frame_s_) {
    const double rate = 1 / (now_s - last_frame_s_);
    fps_ = fps_ == 0 ? rate : (1 - kFpsSmoothing) * fps_ + kFpsSmoothing * rate;
  }
  last_frame_s_ = now_s;
}

void ViewerState::restart_if_needed() {
  if (!needs_restart_) return;
  if (mode_ == Mode::kFloaters && !fresh_floaters_ && !worker_.is_idle()) {
    // The live simulation follows new parameters, equations and clips itself (through the
    // control block): its floaters settle on the changed surface.
    needs_restart_ = false;
    cancel_now_ = false;
    return;
  }
  // Continuous changes (dragging, animation) must not cancel a job before it has shown its
  // first result, or nothing would ever be drawn while they last.
  // A mesh job's first result counts once it is posted and the window is due to take the next
  // live result within about two carries' time: the next carry starts from it while the window
  // still draws the one before (start_mesh_job), so carrying and drawing overlap instead of
  // taking turns, and no carry is made only to be replaced before it is shown.
  const auto posted = mode_ == Mode::kMesh ? mesh_box_.peek() : nullptr;
  const bool posted_in_time =
      posted && posted->generation == generation_ &&
      last_update_s_ >= last_live_frame_s_ + live_frame_interval_s_ - 2 * posted->carry_seconds;
  const bool first_result_shown =
      (mode_ == Mode::kRaytrace && preview_ && preview_->generation == generation_) ||
      (mode_ == Mode::kMesh && mesh_ && mesh_->generation == generation_) || posted_in_time;
  if (cancel_now_ || first_result_shown || worker_.is_idle()) restart_job();
}

void ViewerState::restart_job() {
  ++generation_;
  needs_restart_ = false;
  cancel_now_ = false;
  fresh_floaters_ = false;
  switch (mode_) {
    case Mode::kRaytrace:
      start_preview_job();
      break;
    case Mode::kMesh:
      start_mesh_job();
      break;
    case Mode::kFloaters:
      start_floater_job();
      break;
  }
}

bool ViewerState::collect_results(double now_s) {
  bool is_new = false;
  if (auto p = preview_box_.take()) {
    preview_ = std::move(p);
    is_new = true;
  }
  // Live results (floater steps, improver steps) are taken at most once per live frame
  // interval: with software OpenGL drawing them can cost more than computing them.
  if (now_s - last_live_frame_s_ < live_frame_interval_s_) return is_new;
  if (auto m = mesh_box_.take()) {
    count_mesh_update(*m, now_s);
    mesh_ = std::move(m);
    mesh_wants_frame_->store(true);
    last_live_frame_s_ = now_s;
    is_new = true;
  }
  if (auto f = floater_box_.take()) {
    floaters_ = std::move(f);
    floater_control_->wants_frame = true;
    last_live_frame_s_ = now_s;
    is_new = true;
  }
  return is_new;
}

void ViewerState::count_mesh_update(const MeshFrame& m, double now_s) {
  const bool is_new_job = !mesh_ || mesh_->generation != m.generation;
  if (is_new_job && m.carried) ++mesh_carried_;
  if (is_new_job && !m.carried && !m.rebuild_reason.empty()) ++mesh_rebuilt_;
  // An improved mesh: a carried one, or the end of a rebuild's improvement.
  const bool is_improved =
      (is_new_job && m.carried) || (!m.carried && m.is_final && m.improver_steps > 0);
  if (is_improved) mesh_update_times_.push_back(now_s);
  std::erase_if(mesh_update_times_, [&](double t) { return t < now_s - kMeshRateWindow; });
}

void ViewerState::start_preview_job() {
  RenderOptions options = look_;
  options.camera = surface_.camera;
  options.threads = threads_;
  const Surface surface = surface_;
  const int width = viewport_w_, height = viewport_h_;
  const std::uint64_t generation = generation_;
  // The overlay is traced with the surface, so the surface hides it exactly.
  std::shared_ptr<const SingularFrame> singular = this->singular();
  if (singular) options.singular_overlay = SingularOverlay{.set = singular->set};
  Mailbox<PreviewFrame>* box = &preview_box_;
  worker_.submit([=](std::stop_token stop) mutable {
    // Coarse first so something appears at once, then refine while nothing changes.
    for (const int divisor : {8, 4, 2, 1}) {
      options.width = std::max(1, (width + divisor / 2) / divisor);
      options.height = std::max(1, (height + divisor / 2) / divisor);
      auto frame = std::make_shared<PreviewFrame>();
      frame->divisor = divisor;
      frame->generation = generation;
      frame->singular = singular;
      frame->image = render_surface(surface, options, &frame->stats, stop);
      if (stop.stop_requested()) return;
      box->post(std::move(frame));
    }
  });
}

void ViewerState::start_floater_job() {
  std::shared_ptr<FloaterControl> control = floater_control_;
  control->wants_frame = true;
  const std::uint64_t generation = generation_;
  Mailbox<FloaterFrame>* box = &floater_box_;
  JobWorker* worker = &worker_;
  worker_.submit([control, generation, box, worker](std::stop_token stop) {
    Surface surface;
    FloaterOptions options;
    std::uint64_t surface_version, params_version, options_version, reset_version;
    {
      std::lock_guard lock(control->mutex);
      surface = control->surface;
      options = control->options;
      surface_version = control->surface_version;
      params_version = control->params_version;
      options_version = control->options_version;
      reset_version = control->reset_version;
    }
    FloaterSystem system(surface, options, stop);
    RateMeter rate;
    std::vector<double> next;
    while (!stop.stop_requested()) {
      bool new_surface = false, new_params = false, new_options = false, reset = false;
      {
        std::lock_guard lock(control->mutex);
        if (control->surface_version != surface_version) {
          surface = control->surface;
          surface_version = control->surface_version;
          params_version = control->params_version;
          new_surface = true;
        } else if (control->params_version != params_version) {
          surface = control->surface;
          params_version = control->params_version;
          new_params = true;
        }
        if (control->options_version != options_version) {
          options = control->options;
          options_version = control->options_version;
          new_options = true;
        }
        reset = control->reset_version != reset_version;
        reset_version = control->reset_version;
      }
      try {
        if (new_options) system.set_options(options);
        if (new_surface) system.set_surface(surface);
      } catch (const std::exception& e) {
        // A rejected option or surface: keep simulating what we have and say why.
        worker->post_error(e.what());
      }
      if (reset) system.reset();
      StepStats stats;
      if (new_params) {
        const auto& next_values = surface.field.parameter_values();
        const auto current = system.parameters();
        bool glide = current.size() == next_values.size();
        for (size_t k = 0; glide && k < next_values.size(); ++k) {
          const ParamSpec& r = surface.ranges[k];
          glide = std::abs(next_values[k] - current[k]) <= kGlideFraction * (r.max - r.min);
        }
        if (glide) {
          stats = system.step(next_values);
        } else {
          system.set_parameters(next_values);
          stats = system.step();
        }
      } else {
        stats = system.step();
      }
      const double steps_per_second = rate.tick();
      if (control->wants_frame.exchange(false)) {
        auto frame = std::make_shared<FloaterFrame>();
        const auto p = system.positions();
        const auto n = system.normals();
        const auto r = system.radii();
        frame->positions.assign(p.begin(), p.end());
        frame->normals.assign(n.begin(), n.end());
        frame->radii.assign(r.begin(), r.end());
        frame->last = stats;
        frame->steps_per_second = steps_per_second;
        frame->nominal_radius = system.nominal_radius();
        frame->generation = generation;
        frame->surface_version = surface_version;
        frame->params_version = params_version;
        box->post(std::move(frame));
      }
      if (stats.converged && !control->is_animating) {
        // At rest nothing moves: wait for a change instead of burning a core.
        std::unique_lock lock(control->mutex);
        control->changed.wait_for(lock, stop, std::chrono::milliseconds(50), [&] {
          return control->surface_version != surface_version ||
                 control->params_version != params_version ||
                 control->options_version != options_version ||
                 control->reset_version != reset_version;
        });
      }
    }
  });
}

void ViewerState::start_mesh_job() {
  // The recipe of `zeroset mesh` (mesh_surface) with the viewer's step limit, shown as it goes.
  MeshSettings settings = mesh_settings_;
  const bool with_curves = settings.curves;
  settings.curves = true;  // the frames hide them (set_mesh below); carrying needs them
  MeshRun run;
  run.threads = threads_;
  run.auto_steps = kLiveImproveSteps;
  run.survey = false;  // surveyed on the viewer's own schedule (survey_if_due)
  const bool is_improving = improve_options(settings, run.auto_steps).max_steps > 0;
  const Surface surface = surface_;
  const std::uint64_t generation = generation_;
  const std::uint64_t structure = mesh_structure_;
  Mailbox<MeshFrame>* box = &mesh_box_;
  std::shared_ptr<std::atomic<bool>> wants_frame = mesh_wants_frame_;
  wants_frame->store(true);
  const int threads = threads_;
  // Only the parameters changed since the mesh on screen was made: carry it (docs/viewer.md,
  // live meshes), rebuilding only when that fails.
  // The newest mesh: one posted and not yet taken by the window is newer than the one shown.
  std::shared_ptr<const MeshFrame> previous, latest = mesh_box_.peek();
  if (!latest) latest = mesh_;
  if (is_improving && latest && latest->structure == structure && !latest->mesh.empty() &&
      latest->surface.field.parameter_values() != surface.field.parameter_values())
    previous = latest;
  worker_.submit([=](std::stop_token stop) {
    auto new_frame = [&]() {
      auto frame = std::make_shared<MeshFrame>();
      frame->surface = surface;
      frame->structure = structure;
      frame->generation = generation;
      return frame;
    };
    // The frame shows the curves only when the settings say so; carrying needs them always.
    auto set_mesh = [&](MeshFrame& frame, Mesh mesh) {
      frame.mesh = std::move(mesh);
      if (!with_curves) frame.hidden_curves = std::move(frame.mesh.curves), frame.mesh.curves = {};
    };
    // The first frame of the job (already posted): later frames copy it with the improved mesh.
    std::shared_ptr<MeshFrame> first;
    auto post_improved = [&](Mesh mesh, const ImproveStats& stats, int steps, bool is_final) {
      auto next = std::make_shared<MeshFrame>(*first);
      set_mesh(*next, std::move(mesh));
      compute_field_normals(next->mesh, surface, threads);
      next->improve = stats;
      next->improver_steps = steps;
      next->is_final = is_final;
      box->post(std::move(next));
    };
    // Step by step so the user watches the vertices move: a copy goes to the UI whenever it
    // has taken the previous one. The remesher changes the connectivity as it goes: one frame
    // when it is done.
    MeshRun steps = run;
    steps.on_improver_step = [&](const MeshImprover& improver, int count, bool done) {
      if (done || wants_frame->exchange(false))
        post_improved(improver.mesh(), improver.stats(), count, done);
    };
    auto post_remeshed = [&](Mesh mesh, const std::optional<MeshImprovement>& improved) {
      if (stop.stop_requested()) return;
      if (!improved) {
        post_improved(std::move(mesh), first->improve, first->improver_steps, true);
      } else if (improved->improver == Improver::kRemesh) {
        post_improved(std::move(mesh), improved->summary(),
                      first->improver_steps + improved->remesh.iterations, true);
      }
    };
    std::string reason;
    std::optional<CarrySingularSet> singular;
    if (previous) {
      Mesh from = previous->mesh;
      if (!previous->hidden_curves.empty()) from.curves = previous->hidden_curves;
      const ImproveOptions improve = improve_options(settings, run.auto_steps);
      const CarryOptions carry{.improve_steps = std::min(kCarryImproveSteps, improve.max_steps),
                               .improve = improve,
                               .threads = threads,
                               .from_singular = previous->singular};
      CarryResult r = carry_mesh(from, previous->surface, surface, carry, stop);
      if (stop.stop_requested()) return;
      if (r.carried()) {
        // Shown at once; while the parameters stay, the improver goes on to rest from here.
        first = new_frame();
        set_mesh(*first, r.mesh);
        first->polygonize = previous->polygonize;
        first->crossings = previous->crossings;
        first->improve = r.improve;
        first->improver_steps = r.improve.steps;
        first->carried = true;
        first->carry_seconds = r.seconds;
        first->singular = r.singular;
        first->is_final = r.improve.converged;
        box->post(first);
        if (first->is_final) return;
        // While a parameter moves the next value comes within a frame or two and cancels
        // this job: improving meanwhile would only take the core that draws.
        const auto until = std::chrono::steady_clock::now() + kCarriedRestDelay;
        while (!stop.stop_requested() && std::chrono::steady_clock::now() < until)
          std::this_thread::sleep_for(std::chrono::milliseconds(5));
        const auto improved = improve_surface_mesh(r.mesh, surface, settings, steps, nullptr,
                                                   first->improver_steps, stop);
        post_remeshed(std::move(r.mesh), improved);
        return;
      }
      reason = std::move(r.reason);
      singular = std::move(r.singular);
    }
    steps.on_polygonized = [&](const MeshResult& made) {
      first = new_frame();
      set_mesh(*first, made.mesh);
      first->polygonize = made.polygonize;
      if (made.crossings) first->crossings = *made.crossings;
      first->rebuild_reason = reason;
      first->singular = std::move(singular);
      first->is_final = !is_improving || made.mesh.empty();
      box->post(first);
    };
    MeshResult made = mesh_surface(surface, settings, steps, stop);
    if (first && !first->is_final) post_remeshed(std::move(made.mesh), made.improvement);
  });
}

bool ViewerState::is_settled() const {
  if (needs_restart_ || survey_pending_ || !singular_is_current()) return false;
  switch (mode_) {
    case Mode::kRaytrace:
      return preview_ && preview_->generation == generation_ && preview_->divisor == 1 &&
             preview_->singular == singular();
    case Mode::kMesh:
      return mesh_ && mesh_->generation == generation_ && mesh_->is_final;
    case Mode::kFloaters: {
      if (!floaters_ || floaters_->generation != generation_ || !floaters_->last.converged)
        return false;
      std::lock_guard lock(floater_control_->mutex);
      return floaters_->surface_version == floater_control_->surface_version &&
             floaters_->params_version == floater_control_->params_version;
    }
  }
  return false;
}

ViewerStats ViewerState::stats() const {
  ViewerStats s;
  s.mode = mode_;
  s.fps = fps_;
  s.draw_seconds = draw_seconds_;
  s.is_busy = !is_settled();
  s.show_singular = display_.show_singular;
  s.singular = singular();
  s.singular_is_current = singular_is_current();
  // Only the current job's floaters count: a frame of a job that a settings change has replaced
  // would let `steps N` end on the old job's step count.
  if (floaters_ && floaters_->generation == generation_) {
    s.floater_count = floaters_->positions.size();
    s.floater_steps = floaters_->last.step;
    s.steps_per_second = floaters_->steps_per_second;
    s.median_residual = floaters_->last.median_residual;
    s.max_residual = floaters_->last.max_residual;
    s.converged = floaters_->last.converged;
    s.nominal_radius = floaters_->nominal_radius;
  }
  if (mesh_) {
    s.mesh_vertices = mesh_->mesh.vertex_count();
    s.mesh_triangles = mesh_->mesh.triangle_count();
    s.improver_steps = mesh_->improver_steps;
    s.polygonize_seconds = mesh_->polygonize.seconds_total;
    s.mesh_update = mesh_->carried
                        ? fmt::format("carried in {:.0f} ms", 1000 * mesh_->carry_seconds)
                    : !mesh_->rebuild_reason.empty() ? "rebuilt: " + mesh_->rebuild_reason
                                                     : "built";
  }
  const double since = last_update_s_ - kMeshRateWindow;
  const auto recent = std::count_if(mesh_update_times_.begin(), mesh_update_times_.end(),
                                    [&](double t) { return t >= since; });
  s.mesh_updates_per_second = static_cast<double>(recent) / kMeshRateWindow;
  s.mesh_carried = mesh_carried_;
  s.mesh_rebuilt = mesh_rebuilt_;
  if (preview_) {
    s.preview_divisor = preview_->divisor;
    s.preview_seconds = preview_->stats.seconds;
  }
  return s;
}

}  // namespace zeroset::viewer
