// The viewer's settings: mode, animation, floaters, mesh, display and look, and how they are
// read from and written to a scene file.
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <thread>

#include "viewer_state.h"
#include "viewer_state_detail.h"
#include "zeroset/error.h"
#include "zeroset/floaters/settings.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/render/settings.h"
#include "zeroset/surface/json_read.h"

namespace zeroset::viewer {
namespace {

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

// Animation speed in ranges per second: the command and scene files share the rule.
void check_speed(double speed) {
  if (!(speed > 0 && speed <= 100))
    throw SettingError("speed", fmt::format("{}", speed), "must lie in (0, 100] ranges per second");
}

// The scene file's key of a look setting under "viewer" (the GL modes draw the diffuse colours
// and the background).
std::string viewer_key(const std::string& render_key) {
  const size_t slash = render_key.find("/diffuse");
  return slash == std::string::npos ? render_key : render_key.substr(0, slash);
}

}  // namespace

void validate_display(const DisplaySettings& d) {
  if (!(d.disk_scale > 0 && d.disk_scale <= 10))
    throw SettingError("disk-scale", fmt::format("{}", d.disk_scale), "must lie in (0, 10]");
  if (!(d.point_size_px >= 1 && d.point_size_px <= 64))
    throw SettingError("point-size", fmt::format("{}", d.point_size_px),
                       "must lie in [1, 64] pixels");
}

void check_live_limits(const FloaterOptions& o) {
  if (o.max_count > kMaxLiveFloaters)
    throw SettingError("max_count", std::to_string(o.max_count),
                       fmt::format("the viewer simulates at most {} floaters live (zeroset "
                                   "sample takes up to {})",
                                   kMaxLiveFloaters, kMaxFloaterCount));
}

void check_live_limits(const MeshSettings& m) {
  if (m.cells < kMinLiveCells || m.cells > kMaxLiveCells)
    throw SettingError("cells", std::to_string(m.cells),
                       fmt::format("the viewer meshes live with {} to {} cells (zeroset mesh "
                                   "takes {} to {})",
                                   kMinLiveCells, kMaxLiveCells, kMinMeshCells, kMaxMeshCells));
}

// ---- modes, animation, settings ----------------------------------------------------------------

void ViewerState::set_mode(Mode mode) {
  if (mode == mode_) return;
  mode_ = mode;
  ++mesh_structure_;
  cancel_now_ = true;
  needs_restart_ = true;
  fresh_floaters_ = true;
}

bool ViewerState::play(std::string_view parameter) {
  return guard("play", [&] {
    if (has_keyframes()) {
      if (!parameter.empty())
        throw InvalidArgument(
            fmt::format("the keyframes animate this scene, not '{}' alone "
                        "(keyframe clear removes them)",
                        parameter));
      (void)keyframe_tracks();  // they still fit the surface
      animation_.is_playing = true;
      // Without loop a finished animation stopped at an end: play it back the other way.
      if ((animation_.direction > 0 && key_time_ >= 1) ||
          (animation_.direction < 0 && key_time_ <= 0))
        animation_.direction = -animation_.direction;
      return;
    }
    if (surface_.ranges.empty()) throw InvalidArgument("the surface has no parameter to animate");
    std::string name(parameter.empty() ? animation_.parameter : parameter);
    if (name.empty()) name = surface_.ranges.front().name;
    if (surface_.field.parameter_index(name) < 0)
      throw InvalidArgument(fmt::format("the surface has no parameter '{}'", name));
    animation_.parameter = name;
    animation_.is_playing = true;
    // Without loop a finished animation stopped at an end: play it back the other way.
    const int index = surface_.field.parameter_index(name);
    const ParamSpec& r = surface_.ranges[index];
    const double value = surface_.field.parameter_values()[index];
    if ((animation_.direction > 0 && value >= r.max) ||
        (animation_.direction < 0 && value <= r.min))
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
    check_speed(ranges_per_second);
    animation_.speed = ranges_per_second;
  });
}

void ViewerState::advance_animation(double dt) {
  if (!animation_.is_playing) return;
  if (has_keyframes()) return advance_keyframes(dt);
  const int index = surface_.field.parameter_index(animation_.parameter);
  if (index < 0) {
    animation_.is_playing = false;
    return;
  }
  const ParamSpec& r = surface_.ranges[index];
  double v = surface_.field.parameter_values()[index] +
             animation_.direction * animation_.speed * (r.max - r.min) * dt;
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
    validate_settings(options);
    check_live_limits(options);
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
    validate_settings(settings);
    check_live_limits(settings);
    mesh_settings_ = settings;
    ++mesh_structure_;
    if (mode_ == Mode::kMesh) {
      needs_restart_ = true;
      cancel_now_ = true;
    }
  });
}

bool ViewerState::set_settings(std::string_view object, const json& entries,
                               std::string_view action, std::optional<int> max_steps) {
  const std::string origin(action);
  try {
    if (object == "floaters") {
      FloaterOptions o = floater_options_;
      apply_floater_settings(entries, o, origin);
      return set_floater_options(o);
    }
    if (object == "mesh") {
      MeshSettings m = mesh_settings_;
      apply_mesh_settings(entries, m, origin);
      if (max_steps) m.max_improve_steps = *max_steps;
      return set_mesh_settings(m);
    }
    set_status(fmt::format("{}: '{}': expected floaters or mesh", action, object), true);
    return false;
  } catch (const BadInput& e) {
    // The reader's message already names the action (its origin) and the key.
    set_status(e.what(), true);
    return false;
  } catch (const std::exception& e) {
    set_status(fmt::format("{}: {}", action, e.what()), true);
    return false;
  }
}

json ViewerState::settings_object(std::string_view object) const {
  if (object == "floaters") return floater_settings_to_json(floater_options_);
  if (object == "mesh") return mesh_settings_to_json(mesh_settings_);
  return json::object();
}

bool ViewerState::set_display(const DisplaySettings& display) {
  return guard("display", [&] {
    validate_display(display);
    display_ = display;
  });
}

bool ViewerState::set_look(const RenderOptions& look) {
  return guard("look", [&] {
    validate_settings(look);
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
      l.direction =
          Vec3(l.direction.dot(v.right), l.direction.dot(v.up), -l.direction.dot(v.forward));
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

// ---- settings (scene files) --------------------------------------------------------------------

void ViewerState::apply_settings(const json& settings, const std::string& origin) {
  if (!settings.is_object()) return;
  // The library's readers validate as for the command line; then the live limits.
  auto live = [&](const auto& read, const std::string& object) {
    try {
      check_live_limits(read);
    } catch (const SettingError& e) {
      fail(origin, "/" + object + "/" + e.key(), e.why());
    }
  };
  if (settings.contains("floaters")) {
    apply_floater_settings(settings["floaters"], floater_options_, origin);
    live(floater_options_, "floaters");
  }
  if (settings.contains("mesh")) {
    apply_mesh_settings(settings["mesh"], mesh_settings_, origin);
    live(mesh_settings_, "mesh");
  }
  if (settings.contains("animation")) {
    const json& a = settings["animation"];
    if (!a.is_object()) fail(origin, "/animation", "expected an object");
    if (a.contains("parameter"))
      animation_.parameter = json_read::string(a["parameter"], origin, "/animation/parameter");
    if (a.contains("speed")) {
      const double s = number(a["speed"], origin, "/animation/speed");
      try {
        check_speed(s);
      } catch (const SettingError& e) {
        fail(origin, "/animation/speed", e.why());
      }
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
      display_.disk_scale = number(v["disk_scale"], origin, "/viewer/disk_scale");
      try {
        validate_display(display_);
      } catch (const SettingError& e) {
        fail(origin, "/viewer/disk_scale", e.why());
      }
    }
    if (v.contains("wireframe"))
      display_.wireframe = boolean(v["wireframe"], origin, "/viewer/wireframe");
    if (v.contains("show_singular"))
      display_.show_singular = boolean(v["show_singular"], origin, "/viewer/show_singular");
    if (v.contains("lights_follow_camera"))
      set_lights_follow_camera(
          boolean(v["lights_follow_camera"], origin, "/viewer/lights_follow_camera"));
    if (v.contains("front"))
      look_.front.diffuse = setting_color(v["front"], origin, "/viewer/front");
    if (v.contains("back")) look_.back.diffuse = setting_color(v["back"], origin, "/viewer/back");
    if (v.contains("background"))
      look_.background = setting_color(v["background"], origin, "/viewer/background");
    try {
      validate_settings(look_);
    } catch (const SettingError& e) {
      fail(origin, "/viewer/" + viewer_key(e.key()), e.why());
    }
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
  s["mesh"] = mesh_settings_to_json(mesh_settings_);
  json& a = s["animation"];
  if (!a.is_object()) a = json::object();
  if (!animation_.parameter.empty()) a["parameter"] = animation_.parameter;
  a["speed"] = animation_.speed;
  a["loop"] = animation_.loop;
  if (keyframes_.empty())
    a.erase("keyframes");
  else
    a["keyframes"] = keyframes_;
  json& v = s["viewer"];
  if (!v.is_object()) v = json::object();
  v["mode"] = std::string(viewer::to_string(mode_));
  v["draw"] = display_.draw_points ? "points" : "disks";
  v["disk_scale"] = display_.disk_scale;
  v["wireframe"] = display_.wireframe;
  v["show_singular"] = display_.show_singular;
  v["lights_follow_camera"] = lights_follow_camera();
  v["front"] = color_json(look_.front.diffuse);
  v["back"] = color_json(look_.back.diffuse);
  v["background"] = color_json(look_.background);
  return s;
}

Scene ViewerState::scene() const { return Scene{surface_, settings()}; }

}  // namespace zeroset::viewer
