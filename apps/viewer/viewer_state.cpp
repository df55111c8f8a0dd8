#include "viewer_state.h"

#include <fmt/core.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "camera_control.h"
#include "commands.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/floaters/ply.h"
#include "zeroset/floaters/settings.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/mesh_io.h"
#include "zeroset/mesh/mesh_ops.h"
#include "zeroset/render/pov_export.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/json_read.h"

namespace zeroset::viewer {

std::string_view to_string(Mode mode) {
  switch (mode) {
    case Mode::kFloaters: return "floaters";
    case Mode::kMesh: return "mesh";
    case Mode::kRaytrace: return "raytrace";
  }
  return "raytrace";
}

Mode parse_mode(std::string_view text, std::string_view flag) {
  if (text == "floaters") return Mode::kFloaters;
  if (text == "mesh") return Mode::kMesh;
  if (text == "raytrace" || text == "raytraced" || text == "ray") return Mode::kRaytrace;
  throw InvalidArgument(std::string(flag), std::string(text),
                        "expected floaters, mesh or raytrace");
}

// What the UI thread tells the floater job. The job polls it before every step; versions say
// what changed since the job last looked.
struct ViewerState::FloaterControl {
  std::mutex mutex;
  std::condition_variable_any changed;
  Surface surface;                  // the latest surface, parameters included
  std::uint64_t surface_version = 0;  // new equation or clip
  std::uint64_t params_version = 0;   // new parameter values
  FloaterOptions options;
  std::uint64_t options_version = 0;
  std::uint64_t reset_version = 0;
  std::atomic<bool> wants_frame{true};  // the UI took the last frame: post the next one
  // A parameter is being animated: keep stepping even when at rest, since the next value is
  // due any moment (the UI thread sets it once per frame).
  std::atomic<bool> is_animating{false};
};

namespace {

// A light grey-blue background: both the orange front and the blue back stand out on it.
const Color kBackground(0.74, 0.76, 0.80);

// A parameter jump larger than this fraction of its range is applied at once (floaters
// re-settle through the φF term) rather than through the F_q·q̇ term, which is a first-order
// prediction and overshoots for large steps.
constexpr double kGlideFraction = 0.05;

// Thrown by a command whose action failed (and already set the error status).
struct ActionFailed {};

// Frame rate estimate smoothing (exponential, per frame).
constexpr double kFpsSmoothing = 0.1;

using json = nlohmann::json;

using json_read::boolean;
using json_read::fail;
using json_read::number;

Color setting_color(const json& j, const std::string& origin, const std::string& where) {
  if (!j.is_array() || j.size() != 3) fail(origin, where, "expected [r, g, b]");
  Color c;
  for (int k = 0; k < 3; ++k) c[k] = number(j[k], origin, fmt::format("{}/{}", where, k));
  return c;
}

json color_json(const Color& c) { return json::array({c.x(), c.y(), c.z()}); }

// One range per parameter, in the field's order (sliders and the animation index them so),
// each containing the parameter's value.
void match_ranges_to_field(Surface& s) {
  std::vector<ParamSpec> ranges;
  const auto& names = s.field.parameter_names();
  const auto& values = s.field.parameter_values();
  for (size_t i = 0; i < names.size(); ++i) {
    auto it = std::find_if(s.ranges.begin(), s.ranges.end(),
                           [&](const ParamSpec& r) { return r.name == names[i]; });
    ParamSpec r = it != s.ranges.end() && it->min < it->max
                      ? *it
                      : ParamSpec{names[i], values[i], values[i] - 1, values[i] + 1};
    r.value = values[i];
    r.min = std::min(r.min, r.value);
    r.max = std::max(r.max, r.value);
    ranges.push_back(r);
  }
  s.ranges = std::move(ranges);
}

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
                   {"polygonize_seconds", polygonize_seconds}};
      break;
    case Mode::kRaytrace:
      j["raytrace"] = {{"divisor", preview_divisor}, {"seconds", preview_seconds}};
      break;
  }
  return j;
}

// ---- construction ------------------------------------------------------------------------------

ViewerState::ViewerState(Scene scene, std::optional<Mode> mode, int threads,
                         const std::string& origin)
    : threads_(threads), floater_control_(std::make_shared<FloaterControl>()) {
  look_.lights = default_lights();  // explicit: the GL modes read look_.lights
  look_.background = kBackground;
  floater_options_.threads = floater_threads();
  open_scene(std::move(scene), origin);
  if (mode) mode_ = *mode;
}

ViewerState::~ViewerState() = default;

void ViewerState::open_scene(Scene scene, const std::string& origin) {
  scene.surface.field.require_parameters();
  // Settings first: a malformed scene must leave the current state untouched.
  const Animation animation = animation_;
  const FloaterOptions floater_options = floater_options_;
  const MeshSettings mesh_settings = mesh_settings_;
  const DisplaySettings display = display_;
  const RenderOptions look = look_;
  const Mode mode = mode_;
  try {
    apply_settings(scene.settings, origin);
  } catch (...) {
    animation_ = animation;
    floater_options_ = floater_options;
    mesh_settings_ = mesh_settings;
    display_ = display;
    look_ = look;
    mode_ = mode;
    throw;
  }
  extra_settings_ = scene.settings.is_object() ? scene.settings : json::object();
  surface_ = std::move(scene.surface);
  match_ranges_to_field(surface_);
  ensure_bounded_clip();
  surface_.camera = with_explicit_distance(surface_.camera, surface_.scene_radius());
  home_camera_ = surface_.camera;
  equation_text_ = surface_.field.source();
  equation_error_.clear();
  if (surface_.field.parameter_index(animation_.parameter) < 0) {
    animation_.parameter.clear();
    animation_.is_playing = false;
  }
  fresh_floaters_ = true;
  cancel_now_ = true;
  surface_changed(true);
}

void ViewerState::ensure_bounded_clip() {
  if (surface_.clip.is_bounded()) return;
  // Every mode needs a finite volume; a unit-scale ball suits most equations people type.
  surface_.clip = Clip::sphere(2.0);
  set_status("the surface had no bounded clip: using sphere:2 (change it under Clip)");
}

// ---- guard and status --------------------------------------------------------------------------

bool ViewerState::guard(std::string_view action, const std::function<void()>& body) {
  try {
    body();
    return true;
  } catch (const ActionFailed&) {
    // A nested action failed and already said why.
  } catch (const std::bad_alloc&) {
    set_status(fmt::format("{}: out of memory", action), true);
  } catch (const std::exception& e) {
    set_status(fmt::format("{}: {}", action, e.what()), true);
  } catch (...) {
    set_status(fmt::format("{}: unknown error", action), true);
  }
  return false;
}

void ViewerState::set_status(std::string text, bool is_error) {
  status_ = {std::move(text), is_error};
  if (sink_) sink_(status_);
}

// ---- surface -----------------------------------------------------------------------------------

bool ViewerState::set_equation(const std::string& text) {
  return guard("equation", [&] {
    // The field keeps what the user typed, right or wrong; only a good equation replaces
    // the surface.
    equation_text_ = text;
    ParseResult r = parse_field(text);
    if (!r.ok()) {
      equation_error_ = r.format();
      const size_t eol = equation_error_.find('\n');
      throw BadInput(equation_error_.substr(0, eol) + " (the last good surface stays)");
    }
    Surface s = surface_;
    s.name.clear();
    s.title.clear();
    s.singular_points_fn = nullptr;
    s.field = std::move(*r.field);
    // Parameters the user already tuned keep their values and ranges.
    std::vector<ParamSpec> ranges;
    std::string introduced;
    for (const auto& name : s.field.parameter_names()) {
      auto old = std::find_if(surface_.ranges.begin(), surface_.ranges.end(),
                              [&](const ParamSpec& p) { return p.name == name; });
      ParamSpec spec = old != surface_.ranges.end() ? *old : ParamSpec{name, 1.0, 0.0, 2.0};
      if (old == surface_.ranges.end()) introduced += (introduced.empty() ? "" : ", ") + name;
      s.field.set_parameter(name, spec.value);
      ranges.push_back(spec);
    }
    s.ranges = std::move(ranges);
    s.field.require_parameters();
    surface_ = std::move(s);
    equation_error_.clear();
    cancel_now_ = true;
    if (surface_.field.parameter_index(animation_.parameter) < 0) {
      animation_.parameter.clear();
      animation_.is_playing = false;
    }
    surface_changed(true);
    set_status(introduced.empty()
                   ? "equation accepted"
                   : fmt::format("equation accepted; new parameter(s) {} start at 1", introduced));
  });
}

bool ViewerState::select_catalog(std::string_view name) {
  return guard("catalog", [&] {
    const CatalogEntry* e = find_catalog_entry(name);
    if (!e) {
      std::string names;
      for (const auto& c : catalog()) names += (names.empty() ? "" : ", ") + c.name;
      throw InvalidArgument(fmt::format("no catalog surface '{}' (there are: {})", name, names));
    }
    animation_.is_playing = false;
    open_scene(Scene{make_surface(*e), json::object()}, e->name);
    set_status(fmt::format("opened {}", e->title));
  });
}

bool ViewerState::load_scene(const std::string& path) {
  return guard("load", [&] {
    open_scene(read_scene(path), path);
    set_status(fmt::format("loaded {}", path));
  });
}

bool ViewerState::set_parameter(std::string_view name, double value) {
  return guard("param", [&] {
    const int index = surface_.field.parameter_index(name);
    if (index < 0)
      throw InvalidArgument(fmt::format("the surface has no parameter '{}'", name));
    if (!std::isfinite(value))
      throw InvalidArgument(std::string(name), fmt::format("{}", value), "must be finite");
    surface_.field.set_parameter(index, value);
    ParamSpec& r = surface_.ranges[index];
    r.value = value;
    r.min = std::min(r.min, value);
    r.max = std::max(r.max, value);
    surface_changed(false);
  });
}

bool ViewerState::set_parameter_range(std::string_view name, double min, double max) {
  return guard("range", [&] {
    const int index = surface_.field.parameter_index(name);
    if (index < 0)
      throw InvalidArgument(fmt::format("the surface has no parameter '{}'", name));
    if (!(std::isfinite(min) && std::isfinite(max) && min < max))
      throw InvalidArgument(fmt::format("range of {}: needs finite min < max, got {} .. {}",
                                        name, min, max));
    ParamSpec& r = surface_.ranges[index];
    r.min = min;
    r.max = max;
    const double clamped = std::clamp(r.value, min, max);
    if (clamped != r.value) {
      r.value = clamped;
      surface_.field.set_parameter(index, clamped);
      surface_changed(false);
    }
  });
}

bool ViewerState::set_clip(const Clip& clip) {
  return guard("clip", [&] {
    if (!clip.is_bounded())
      throw InvalidArgument("the clip must be bounded: include a sphere, or planes closing a box");
    Surface s = surface_;
    s.clip = clip;
    s.bounds();  // throws for an empty box
    surface_ = std::move(s);
    surface_changed(true);
  });
}

bool ViewerState::set_clip_specs(const std::vector<std::string>& specs) {
  Clip clip;
  if (!guard("clip", [&] {
        for (const auto& spec : specs) clip.add(spec);
      }))
    return false;
  return set_clip(clip);
}

void ViewerState::surface_changed(bool structure) {
  needs_restart_ = true;
  std::lock_guard lock(floater_control_->mutex);
  floater_control_->surface = surface_;
  if (structure)
    ++floater_control_->surface_version;
  else
    ++floater_control_->params_version;
  floater_control_->changed.notify_all();
}

// ---- modes, animation, settings ----------------------------------------------------------------

void ViewerState::set_mode(Mode mode) {
  if (mode == mode_) return;
  mode_ = mode;
  cancel_now_ = true;
  needs_restart_ = true;
  fresh_floaters_ = true;
}

bool ViewerState::play(std::string_view parameter) {
  return guard("play", [&] {
    if (surface_.ranges.empty()) throw InvalidArgument("the surface has no parameter to animate");
    std::string name(parameter.empty() ? animation_.parameter : parameter);
    if (name.empty()) name = surface_.ranges.front().name;
    if (surface_.field.parameter_index(name) < 0)
      throw InvalidArgument(fmt::format("the surface has no parameter '{}'", name));
    animation_.parameter = name;
    animation_.is_playing = true;
    // Without loop a finished animation stopped at an end: play it back the other way.
    const ParamSpec& r = surface_.ranges[surface_.field.parameter_index(name)];
    if ((animation_.direction > 0 && r.value >= r.max) || (animation_.direction < 0 && r.value <= r.min))
      animation_.direction = -animation_.direction;
  });
}

void ViewerState::pause() { animation_.is_playing = false; }

bool ViewerState::set_animation_parameter(std::string_view parameter) {
  return guard("animate", [&] {
    if (surface_.field.parameter_index(parameter) < 0)
      throw InvalidArgument(fmt::format("the surface has no parameter '{}'", parameter));
    animation_.parameter = std::string(parameter);
  });
}

bool ViewerState::set_speed(double ranges_per_second) {
  return guard("speed", [&] {
    if (!(ranges_per_second > 0 && ranges_per_second <= 100))
      throw InvalidArgument("speed", fmt::format("{}", ranges_per_second),
                            "must lie in (0, 100] ranges per second");
    animation_.speed = ranges_per_second;
  });
}

void ViewerState::advance_animation(double dt) {
  if (!animation_.is_playing) return;
  const int index = surface_.field.parameter_index(animation_.parameter);
  if (index < 0) {
    animation_.is_playing = false;
    return;
  }
  const ParamSpec& r = surface_.ranges[index];
  double v = r.value + animation_.direction * animation_.speed * (r.max - r.min) * dt;
  if (v >= r.max || v <= r.min) {
    const double edge = v >= r.max ? r.max : r.min;
    if (animation_.loop) {
      v = std::clamp(2 * edge - v, r.min, r.max);  // reflect at the end of the range
      animation_.direction = -animation_.direction;
    } else {
      v = edge;
      animation_.is_playing = false;
    }
  }
  set_parameter(animation_.parameter, v);
}

bool ViewerState::set_floater_options(const FloaterOptions& options) {
  return guard("floaters", [&] {
    if (options.max_count < 1 || options.max_count > 2'000'000)
      throw InvalidArgument("max_count", std::to_string(options.max_count),
                            "must lie in [1, 2000000]");
    if (!(options.radius >= 0) || !std::isfinite(options.radius))
      throw InvalidArgument("radius", fmt::format("{}", options.radius),
                            "must be a finite length ≥ 0 (0: chosen from the surface's area)");
    floater_options_ = options;
    floater_options_.threads = floater_threads();
    std::lock_guard lock(floater_control_->mutex);
    floater_control_->options = floater_options_;
    ++floater_control_->options_version;
    floater_control_->changed.notify_all();
  });
}

void ViewerState::reset_floaters() {
  std::lock_guard lock(floater_control_->mutex);
  ++floater_control_->reset_version;
  floater_control_->changed.notify_all();
}

bool ViewerState::set_mesh_settings(const MeshSettings& settings) {
  return guard("mesh", [&] {
    if (settings.cells < 4 || settings.cells > 512)
      throw InvalidArgument("cells", std::to_string(settings.cells), "must lie in [4, 512]");
    if (settings.max_improver_steps < 0 || settings.max_improver_steps > 100000)
      throw InvalidArgument("max_steps", std::to_string(settings.max_improver_steps),
                            "must lie in [0, 100000]");
    mesh_settings_ = settings;
    if (mode_ == Mode::kMesh) {
      needs_restart_ = true;
      cancel_now_ = true;
    }
  });
}

bool ViewerState::set_display(const DisplaySettings& display) {
  return guard("display", [&] {
    if (!(display.disk_scale > 0 && display.disk_scale <= 10))
      throw InvalidArgument("disk-scale", fmt::format("{}", display.disk_scale),
                            "must lie in (0, 10]");
    if (!(display.point_size_px >= 1 && display.point_size_px <= 64))
      throw InvalidArgument("point-size", fmt::format("{}", display.point_size_px),
                            "must lie in [1, 64] pixels");
    display_ = display;
  });
}

bool ViewerState::set_look(const RenderOptions& look) {
  return guard("look", [&] {
    auto check = [](const Color& c, const char* what) {
      if (!c.allFinite() || (c.array() < 0).any() || (c.array() > 1).any())
        throw InvalidArgument(fmt::format("{} colour: components must lie in [0, 1]", what));
    };
    check(look.front.diffuse, "front");
    check(look.back.diffuse, "back");
    check(look.background, "background");
    look_ = look;
    if (mode_ == Mode::kRaytrace) needs_restart_ = true;
  });
}

void ViewerState::set_lights_follow_camera(bool follow) {
  if (follow == lights_follow_camera()) return;
  // Convert the directions so the lights stay where they are at the moment of switching.
  const View v = view();
  for (Light& l : look_.lights) {
    if (l.follows_camera == follow) continue;
    if (follow)
      l.direction = Vec3(l.direction.dot(v.right), l.direction.dot(v.up), -l.direction.dot(v.forward));
    else
      l.direction = v.camera_to_world(l.direction);
    l.follows_camera = follow;
  }
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

bool ViewerState::lights_follow_camera() const {
  return std::all_of(look_.lights.begin(), look_.lights.end(),
                     [](const Light& l) { return l.follows_camera; });
}

// ---- camera ------------------------------------------------------------------------------------

void ViewerState::set_viewport(int width, int height) {
  width = std::max(width, 1);
  height = std::max(height, 1);
  if (width == viewport_w_ && height == viewport_h_) return;
  viewport_w_ = width;
  viewport_h_ = height;
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

bool ViewerState::set_camera(const Camera& camera) {
  return guard("camera", [&] {
    Camera c = camera;
    c.elevation_deg = std::clamp(c.elevation_deg, -kMaxElevationDeg, kMaxElevationDeg);
    c = with_explicit_distance(c, surface_.scene_radius());
    View::from_camera(c, surface_.scene_radius(), viewport_w_, viewport_h_);  // validates
    surface_.camera = c;
    if (mode_ == Mode::kRaytrace) needs_restart_ = true;
  });
}

void ViewerState::orbit(double dx_px, double dy_px) {
  viewer::orbit(surface_.camera, dx_px, dy_px);
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

void ViewerState::pan(double dx_px, double dy_px) {
  viewer::pan(surface_.camera, view(), dx_px, dy_px);
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

void ViewerState::zoom(double factor) {
  if (!(factor > 0) || !std::isfinite(factor)) return;
  viewer::zoom(surface_.camera, factor, surface_.scene_radius());
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

void ViewerState::reset_view() {
  surface_.camera = home_camera_;
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

View ViewerState::view() const {
  return View::from_camera(surface_.camera, surface_.scene_radius(), viewport_w_, viewport_h_);
}

// ---- settings (scene files) --------------------------------------------------------------------

void ViewerState::apply_settings(const json& settings, const std::string& origin) {
  if (!settings.is_object()) return;
  if (settings.contains("floaters"))
    apply_floater_settings(settings["floaters"], floater_options_, origin);
  if (settings.contains("mesh")) {
    const json& m = settings["mesh"];
    if (!m.is_object()) fail(origin, "/mesh", "expected an object");
    if (m.contains("cells"))
      mesh_settings_.cells =
          static_cast<int>(json_read::whole(m["cells"], origin, "/mesh/cells", 4, 512));
    if (m.contains("improve"))
      mesh_settings_.improve = boolean(m["improve"], origin, "/mesh/improve");
  }
  if (settings.contains("animation")) {
    const json& a = settings["animation"];
    if (!a.is_object()) fail(origin, "/animation", "expected an object");
    if (a.contains("parameter"))
      animation_.parameter = json_read::string(a["parameter"], origin, "/animation/parameter");
    if (a.contains("speed")) {
      const double s = number(a["speed"], origin, "/animation/speed");
      if (!(s > 0 && s <= 100)) fail(origin, "/animation/speed", "must lie in (0, 100]");
      animation_.speed = s;
    }
    if (a.contains("loop")) animation_.loop = boolean(a["loop"], origin, "/animation/loop");
  }
  if (settings.contains("viewer")) {
    const json& v = settings["viewer"];
    if (!v.is_object()) fail(origin, "/viewer", "expected an object");
    if (v.contains("mode")) {
      try {
        mode_ = parse_mode(json_read::string(v["mode"], origin, "/viewer/mode"));
      } catch (const InvalidArgument& e) {
        fail(origin, "/viewer/mode", e.what());
      }
    }
    if (v.contains("draw")) {
      const std::string d = json_read::string(v["draw"], origin, "/viewer/draw");
      if (d != "disks" && d != "points") fail(origin, "/viewer/draw", "expected disks or points");
      display_.draw_points = d == "points";
    }
    if (v.contains("disk_scale")) {
      const double s = number(v["disk_scale"], origin, "/viewer/disk_scale");
      if (!(s > 0 && s <= 10)) fail(origin, "/viewer/disk_scale", "must lie in (0, 10]");
      display_.disk_scale = s;
    }
    if (v.contains("wireframe"))
      display_.wireframe = boolean(v["wireframe"], origin, "/viewer/wireframe");
    if (v.contains("lights_follow_camera"))
      set_lights_follow_camera(
          boolean(v["lights_follow_camera"], origin, "/viewer/lights_follow_camera"));
    if (v.contains("front")) look_.front.diffuse = setting_color(v["front"], origin, "/viewer/front");
    if (v.contains("back")) look_.back.diffuse = setting_color(v["back"], origin, "/viewer/back");
    if (v.contains("background"))
      look_.background = setting_color(v["background"], origin, "/viewer/background");
  }
  floater_options_.threads = floater_threads();
  std::lock_guard lock(floater_control_->mutex);
  floater_control_->options = floater_options_;
  ++floater_control_->options_version;
}

int ViewerState::floater_threads() const {
  if (threads_ > 0) return threads_;
  // Half the cores: the other half draws (software OpenGL runs on them too). An OpenMP team
  // that shares its cores with the drawing spins at every barrier while a member waits for a
  // core: measured with 10,000 floaters on Kummer on 2 busy cores, one thread made 59 steps
  // per second and two made 11.
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()) / 2);
}

json ViewerState::settings() const {
  json s = extra_settings_;
  s["floaters"] = floater_settings_to_json(floater_options_);
  json& m = s["mesh"];
  if (!m.is_object()) m = json::object();
  m["cells"] = mesh_settings_.cells;
  m["improve"] = mesh_settings_.improve;
  json& a = s["animation"];
  if (!a.is_object()) a = json::object();
  if (!animation_.parameter.empty()) a["parameter"] = animation_.parameter;
  a["speed"] = animation_.speed;
  a["loop"] = animation_.loop;
  json& v = s["viewer"];
  if (!v.is_object()) v = json::object();
  v["mode"] = std::string(viewer::to_string(mode_));
  v["draw"] = display_.draw_points ? "points" : "disks";
  v["disk_scale"] = display_.disk_scale;
  v["wireframe"] = display_.wireframe;
  v["lights_follow_camera"] = lights_follow_camera();
  v["front"] = color_json(look_.front.diffuse);
  v["back"] = color_json(look_.back.diffuse);
  v["background"] = color_json(look_.background);
  return s;
}

Scene ViewerState::scene() const { return Scene{surface_, settings()}; }

// ---- files -------------------------------------------------------------------------------------

bool ViewerState::save_scene(const std::string& path) {
  return guard("save-scene", [&] {
    if (file_extension(path) != "json")
      throw InvalidArgument("scene file", path, "the name must end in .json");
    write_scene(scene(), path);
    set_status(fmt::format("saved scene {}", path));
  });
}

bool ViewerState::save_floaters(const std::string& path) {
  return guard("save-floaters", [&] {
    if (file_extension(path) != "ply")
      throw InvalidArgument("floaters file", path, "the name must end in .ply");
    if (!floaters_ || floaters_->positions.empty())
      throw InvalidArgument("there are no floaters yet (switch to floaters mode)");
    write_points_ply(path, floaters_->positions, floaters_->normals, floaters_->radii);
    set_status(fmt::format("saved {} floaters to {}", floaters_->positions.size(), path));
  });
}

bool ViewerState::save_mesh(const std::string& path) {
  return guard("save-mesh", [&] {
    if (!mesh_ || mesh_->mesh.empty())
      throw InvalidArgument("there is no mesh yet (switch to mesh mode)");
    write_mesh(mesh_->mesh, path);
    set_status(fmt::format("saved mesh ({} vertices, {} triangles) to {}",
                           mesh_->mesh.vertex_count(), mesh_->mesh.triangle_count(), path));
  });
}

bool ViewerState::save_pov(const std::string& path) {
  return guard("save-pov", [&] {
    if (file_extension(path) != "pov")
      throw InvalidArgument("POV-Ray file", path, "the name must end in .pov");
    RenderOptions o = look_;
    o.camera = surface_.camera;
    o.width = viewport_w_;
    o.height = viewport_h_;
    write_pov_scene(surface_, o, path);
    set_status(fmt::format("saved POV-Ray scene {} (render: povray +W{} +H{} +I{})", path,
                           viewport_w_, viewport_h_, path));
  });
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
  const bool first_result_shown =
      (mode_ == Mode::kRaytrace && preview_ && preview_->generation == generation_) ||
      (mode_ == Mode::kMesh && mesh_ && mesh_->generation == generation_);
  if (cancel_now_ || first_result_shown || worker_.is_idle()) restart_job();
}

void ViewerState::restart_job() {
  ++generation_;
  needs_restart_ = false;
  cancel_now_ = false;
  fresh_floaters_ = false;
  switch (mode_) {
    case Mode::kRaytrace: start_preview_job(); break;
    case Mode::kMesh: start_mesh_job(); break;
    case Mode::kFloaters: start_floater_job(); break;
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

void ViewerState::start_preview_job() {
  RenderOptions options = look_;
  options.camera = surface_.camera;
  options.threads = threads_;
  const Surface surface = surface_;
  const int width = viewport_w_, height = viewport_h_;
  const std::uint64_t generation = generation_;
  Mailbox<PreviewFrame>* box = &preview_box_;
  worker_.submit([=](std::stop_token stop) mutable {
    // Coarse first so something appears at once, then refine while nothing changes.
    for (const int divisor : {8, 4, 2, 1}) {
      options.width = std::max(1, (width + divisor / 2) / divisor);
      options.height = std::max(1, (height + divisor / 2) / divisor);
      auto frame = std::make_shared<PreviewFrame>();
      frame->divisor = divisor;
      frame->generation = generation;
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
    FloaterSystem system(surface, options);
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
  PolygonizeOptions options;
  options.cells = mesh_settings_.cells;
  options.threads = threads_;
  options.compute_normals = true;
  ImproveOptions improve;
  improve.max_steps = mesh_settings_.max_improver_steps;
  improve.threads = threads_;
  const bool is_improving = mesh_settings_.improve && improve.max_steps > 0;
  const Surface surface = surface_;
  const std::uint64_t generation = generation_;
  Mailbox<MeshFrame>* box = &mesh_box_;
  std::shared_ptr<std::atomic<bool>> wants_frame = mesh_wants_frame_;
  wants_frame->store(true);
  const int threads = threads_;
  worker_.submit([=](std::stop_token stop) {
    PolygonizeStats polygonize_stats;
    Mesh mesh = polygonize(surface, options, &polygonize_stats, stop);
    if (stop.stop_requested()) return;
    auto frame = std::make_shared<MeshFrame>();
    frame->mesh = mesh;
    frame->polygonize = polygonize_stats;
    frame->is_final = !is_improving;
    frame->generation = generation;
    box->post(std::move(frame));
    if (!is_improving) return;
    // Step by step so the user watches the vertices move; a copy goes to the UI whenever it
    // has taken the previous one.
    MeshImprover improver(std::move(mesh), surface, improve);
    for (int step = 1; !stop.stop_requested(); ++step) {
      const ImproveStats& stats = improver.step();
      const bool is_done = improver.converged() || step >= improve.max_steps;
      if (is_done) improver.finish();
      if (is_done || wants_frame->exchange(false)) {
        auto next = std::make_shared<MeshFrame>();
        next->mesh = improver.mesh();
        compute_field_normals(next->mesh, surface, threads);
        next->polygonize = polygonize_stats;
        next->improve = stats;
        next->improver_steps = step;
        next->is_final = is_done;
        next->generation = generation;
        box->post(std::move(next));
      }
      if (is_done) return;
    }
  });
}

bool ViewerState::is_settled() const {
  if (needs_restart_) return false;
  switch (mode_) {
    case Mode::kRaytrace:
      return preview_ && preview_->generation == generation_ && preview_->divisor == 1;
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
  if (floaters_) {
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
  }
  if (preview_) {
    s.preview_divisor = preview_->divisor;
    s.preview_seconds = preview_->stats.seconds;
  }
  return s;
}

// ---- commands ----------------------------------------------------------------------------------

bool ViewerState::command(std::string_view line) {
  const CommandLine c = split_command(line);
  if (c.is_empty()) return true;
  return guard(c.name, [&] { command_unguarded(c); });
}

void ViewerState::command_unguarded(const CommandLine& c) {
  const CommandInfo& info = check_command(c);
  if (info.is_frame_loop)
    throw InvalidArgument(fmt::format("'{}' only works in a script (it needs the frame loop)", c.name));
  const auto& a = c.args;
  // The actions report their own failures through the guard; the command fails with them.
  auto require = [](bool ok) {
    if (!ok) throw ActionFailed{};
  };
  const std::string& n = c.name;
  if (n == "equation") {
    require(set_equation(c.rest));
  } else if (n == "catalog") {
    require(select_catalog(a[0]));
  } else if (n == "load") {
    require(load_scene(a[0]));
  } else if (n == "param") {
    require(set_parameter(a[0], parse_number(a[1], a[0])));
  } else if (n == "range") {
    require(set_parameter_range(a[0], parse_number(a[1], "min"), parse_number(a[2], "max")));
  } else if (n == "clip") {
    require(set_clip_specs(a));
  } else if (n == "mode") {
    set_mode(parse_mode(a[0]));
  } else if (n == "play") {
    require(play(a.empty() ? std::string_view{} : std::string_view(a[0])));
  } else if (n == "pause") {
    pause();
  } else if (n == "loop") {
    set_loop(parse_on_off(a[0], "loop"));
  } else if (n == "speed") {
    require(set_speed(parse_number(a[0], "speed")));
  } else if (n == "floaters") {
    if (a.size() == 1 && a[0] == "reset") {
      reset_floaters();
      return;
    }
    FloaterOptions o = floater_options_;
    for (const auto& kv : a) {
      const size_t eq = kv.find('=');
      if (eq == std::string::npos)
        throw InvalidArgument(fmt::format("floaters: expected KEY=VALUE, got '{}'", kv));
      const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
      if (key == "max_count")
        o.max_count = static_cast<std::size_t>(parse_integer(value, key, 1, 2'000'000));
      else if (key == "radius")
        o.radius = parse_number(value, key);
      else if (key == "seed")
        o.seed = static_cast<std::uint64_t>(parse_integer(value, key, 0, 1LL << 53));
      else if (key == "cos_weight")
        o.cos_weight = parse_on_off(value, key);
      else if (key == "clip_projection")
        o.clip_projection = parse_on_off(value, key);
      else if (key == "snap_to_nodes")
        o.snap_to_nodes = parse_on_off(value, key);
      else if (key == "radius_adapt")
        o.radius_adapt = parse_radius_adapt(value, key);
      else
        throw InvalidArgument(fmt::format(
            "floaters: unknown key '{}' (max_count, radius, seed, cos_weight, clip_projection, "
            "snap_to_nodes, radius_adapt)", key));
    }
    require(set_floater_options(o));
  } else if (n == "mesh") {
    MeshSettings m = mesh_settings_;
    for (const auto& kv : a) {
      const size_t eq = kv.find('=');
      if (eq == std::string::npos)
        throw InvalidArgument(fmt::format("mesh: expected KEY=VALUE, got '{}'", kv));
      const std::string key = kv.substr(0, eq), value = kv.substr(eq + 1);
      if (key == "cells")
        m.cells = static_cast<int>(parse_integer(value, key, 4, 512));
      else if (key == "improve")
        m.improve = parse_on_off(value, key);
      else if (key == "max_steps")
        m.max_improver_steps = static_cast<int>(parse_integer(value, key, 0, 100000));
      else
        throw InvalidArgument(fmt::format("mesh: unknown key '{}' (cells, improve, max_steps)", key));
    }
    require(set_mesh_settings(m));
  } else if (n == "draw") {
    if (a[0] != "disks" && a[0] != "points")
      throw InvalidArgument("draw", a[0], "expected disks or points");
    DisplaySettings d = display_;
    d.draw_points = a[0] == "points";
    require(set_display(d));
  } else if (n == "disk-scale") {
    DisplaySettings d = display_;
    d.disk_scale = parse_number(a[0], "disk-scale");
    require(set_display(d));
  } else if (n == "point-size") {
    DisplaySettings d = display_;
    d.point_size_px = parse_number(a[0], "point-size");
    require(set_display(d));
  } else if (n == "wireframe") {
    DisplaySettings d = display_;
    d.wireframe = parse_on_off(a[0], "wireframe");
    require(set_display(d));
  } else if (n == "lights") {
    if (a[0] != "follow" && a[0] != "fixed")
      throw InvalidArgument("lights", a[0], "expected follow or fixed");
    set_lights_follow_camera(a[0] == "follow");
  } else if (n == "color") {
    RenderOptions look = look_;
    const Color rgb(parse_number(a[1], "red"), parse_number(a[2], "green"),
                    parse_number(a[3], "blue"));
    if (a[0] == "front")
      look.front.diffuse = rgb;
    else if (a[0] == "back")
      look.back.diffuse = rgb;
    else if (a[0] == "background")
      look.background = rgb;
    else
      throw InvalidArgument("color", a[0], "expected front, back or background");
    require(set_look(look));
  } else if (n == "camera") {
    Camera cam = surface_.camera;
    cam.azimuth_deg = parse_number(a[0], "azimuth");
    cam.elevation_deg = parse_number(a[1], "elevation");
    if (a.size() == 3) {
      cam.distance = parse_number(a[2], "distance");
      if (!(cam.distance > 0)) throw InvalidArgument("distance", a[2], "must be positive");
    }
    require(set_camera(cam));
  } else if (n == "orbit") {
    Camera cam = surface_.camera;
    cam.azimuth_deg += parse_number(a[0], "azimuth change");
    cam.elevation_deg += parse_number(a[1], "elevation change");
    require(set_camera(cam));
  } else if (n == "zoom") {
    const double f = parse_number(a[0], "zoom");
    if (!(f > 0)) throw InvalidArgument("zoom", a[0], "must be positive");
    zoom(1 / f);
  } else if (n == "pan") {
    pan(parse_number(a[0], "dx"), parse_number(a[1], "dy"));
  } else if (n == "reset-view") {
    reset_view();
  } else if (n == "save-scene") {
    require(save_scene(a[0]));
  } else if (n == "save-mesh") {
    require(save_mesh(a[0]));
  } else if (n == "save-floaters") {
    require(save_floaters(a[0]));
  } else if (n == "save-pov") {
    require(save_pov(a[0]));
  } else {
    throw Error(fmt::format("internal error: command '{}' has no handler", n));
  }
}

}  // namespace zeroset::viewer
