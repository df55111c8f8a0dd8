// The viewer state: opening scenes, the guard, surface edits, saving files and running a
// command. Settings, camera and jobs live in viewer_settings.cpp, viewer_camera.cpp and
// viewer_jobs.cpp.
#include "viewer_state.h"

#include <fmt/core.h>

#include <algorithm>
#include <cmath>

#include "camera_control.h"
#include "commands.h"
#include "viewer_state_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/floaters/ply.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/mesh/mesh_io.h"
#include "zeroset/render/pov_export.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/field_survey.h"

namespace zeroset::viewer {

std::string_view to_string(Mode mode) {
  switch (mode) {
    case Mode::kFloaters:
      return "floaters";
    case Mode::kMesh:
      return "mesh";
    case Mode::kRaytrace:
      return "raytrace";
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

namespace {

using json = nlohmann::json;

void widen_to(ParamSpec& range, double value) {
  range.min = std::min(range.min, value);
  range.max = std::max(range.max, value);
}

// A light grey-blue background: both the orange front and the blue back stand out on it.
const Color kBackground(0.74, 0.76, 0.80);

// One range per parameter, in the field's order (sliders and the animation index them so),
// each containing the parameter's value.
void match_ranges_to_field(Surface& s) {
  s.fit_ranges();
  for (size_t i = 0; i < s.ranges.size(); ++i) widen_to(s.ranges[i], s.field.parameter_values()[i]);
}

}  // namespace

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
  // Keyframes are read as `zeroset animate` reads them, so the viewer opens no scene it refuses.
  json keys = detail::scene_keyframes(scene.settings);
  (void)read_keyframes(scene.settings, scene.surface, detail::keyframe_frames(keys), origin);
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
  keyframes_ = std::move(keys);
  key_time_ = 0;
  surface_ = std::move(scene.surface);
  match_ranges_to_field(surface_);
  clip_is_substitute_ = false;
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
  clip_is_substitute_ = true;
  set_status("the surface had no bounded clip: using sphere:2 (change it under Clip)");
}

// ---- guard and status --------------------------------------------------------------------------

bool ViewerState::guard(std::string_view action, const std::function<void()>& body) {
  try {
    body();
    return true;
  } catch (const detail::ActionFailed&) {
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
      const int old = surface_.field.parameter_index(name);
      if (old >= 0) {
        s.field.set_parameter(name, surface_.field.parameter_values()[old]);
        ranges.push_back(surface_.ranges[old]);
      } else {
        introduced += (introduced.empty() ? "" : ", ") + name;
        s.field.set_parameter(name, 1.0);
        ranges.push_back({name, 0.0, 2.0});
      }
    }
    s.ranges = std::move(ranges);
    s.field.require_parameters();
    try {
      s.clip.update(s.field);  // a clip following the parameters
    } catch (const BadInput&) {
      // The new equation lacks a parameter the clip follows: the clip stays as it is now.
      Clip fixed;
      for (const auto& spec : s.clip.to_specs(true)) fixed.add(spec);
      s.clip = std::move(fixed);
    }
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
    if (index < 0) throw InvalidArgument(fmt::format("the surface has no parameter '{}'", name));
    if (!std::isfinite(value))
      throw InvalidArgument(std::string(name), fmt::format("{}", value), "must be finite");
    Field field = surface_.field;
    field.set_parameter(index, value);
    Clip clip = surface_.clip;
    clip.update(field);  // refused before anything changes
    follow_clip(clip);
    surface_.field = std::move(field);
    surface_.clip = std::move(clip);
    widen_to(surface_.ranges[index], value);
    surface_changed(false);
  });
}

bool ViewerState::set_parameter_range(std::string_view name, double min, double max) {
  return guard("range", [&] {
    const int index = surface_.field.parameter_index(name);
    if (index < 0) throw InvalidArgument(fmt::format("the surface has no parameter '{}'", name));
    if (!(std::isfinite(min) && std::isfinite(max) && min < max))
      throw InvalidArgument(
          fmt::format("range of {}: needs finite min < max, got {} .. {}", name, min, max));
    check_parameter_value(name, min);
    check_parameter_value(name, max);
    ParamSpec& r = surface_.ranges[index];
    r.min = min;
    r.max = max;
    const double value = surface_.field.parameter_values()[index];
    const double clamped = std::clamp(value, min, max);
    if (clamped != value) {
      Field field = surface_.field;
      field.set_parameter(index, clamped);
      Clip clip = surface_.clip;
      clip.update(field);
      follow_clip(clip);
      surface_.field = std::move(field);
      surface_.clip = std::move(clip);
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
    s.clip.update(s.field);
    s.bounds();  // throws for an empty box
    surface_ = std::move(s);
    clip_is_substitute_ = false;
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
  ++surface_version_;
  // The commands' survey takes milliseconds to tens of them on a busy machine: at every value of
  // a moving parameter it would slow every frame, so new values alone are surveyed once they
  // rest, and at most once per kSurveyInterval while they move (update()).
  if (structure) {
    survey_now();
  } else {
    survey_pending_ = true;
    last_param_change_s_ = last_update_s_;
  }
  if (structure) {
    ++mesh_structure_;  // another equation or clip: a mesh is not carried across
    // The set of another equation or clip must not be drawn on this one.
    singular_floor_ = surface_version_;
    singular_ = nullptr;
    singular_cancel_now_ = true;
  }
  std::lock_guard lock(floater_control_->mutex);
  floater_control_->surface = surface_;
  if (structure)
    ++floater_control_->surface_version;
  else
    ++floater_control_->params_version;
  floater_control_->changed.notify_all();
}

void ViewerState::survey_now() {
  survey_pending_ = false;
  last_survey_s_ = last_update_s_;
  const std::string warning =
      survey_warning(surface_, survey_field(surface_)).value_or(std::string());
  if (warning != field_warning_) {
    field_warning_ = warning;
    if (!warning.empty()) set_status("warning: " + warning);
  }
}

void ViewerState::survey_if_due(double now_s) {
  if (survey_pending_ &&
      (now_s - last_param_change_s_ >= kSurveyRest || now_s - last_survey_s_ >= kSurveyInterval))
    survey_now();
}

// ---- files -------------------------------------------------------------------------------------

bool ViewerState::save_scene(const std::string& path) {
  return guard("save-scene", [&] {
    if (file_extension(path) != "json")
      throw InvalidArgument("scene file", path, "the name must end in .json");
    (void)keyframe_tracks();  // keyframes the surface no longer fits would make a bad file
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

// ---- commands ----------------------------------------------------------------------------------

bool ViewerState::command(std::string_view line) {
  const CommandLine c = split_command(line);
  if (c.is_empty()) return true;
  return guard(c.name, [&] {
    const CommandInfo& info = check_command(c);
    if (info.is_frame_loop())
      throw InvalidArgument(
          fmt::format("'{}' only works in a script (it needs the frame loop)", c.name));
    info.run(*this, c);
  });
}

}  // namespace zeroset::viewer
