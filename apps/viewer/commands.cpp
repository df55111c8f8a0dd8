#include "commands.h"

#include <fmt/core.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <tuple>

#include "viewer_state.h"
#include "viewer_state_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/field.h"
#include "zeroset/floaters/floaters.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/surface/settings.h"

namespace zeroset::viewer {

namespace {

// ---- the handlers of the state commands (frame-loop commands are the script runner's) -------

// The actions report their own failures through the guard; the command fails with them.
void require(bool ok) {
  if (!ok) throw detail::ActionFailed{};
}

using Args = std::vector<std::string>;

void run_equation(ViewerState& s, const CommandLine& c) { require(s.set_equation(c.rest)); }
void run_catalog(ViewerState& s, const CommandLine& c) { require(s.select_catalog(c.args[0])); }
void run_load(ViewerState& s, const CommandLine& c) { require(s.load_scene(c.args[0])); }

void run_param(ViewerState& s, const CommandLine& c) {
  const double value = parse_number(c.args[1], c.args[0]);
  check_parameter_value(c.args[0], value);
  require(s.set_parameter(c.args[0], value));
}

void run_range(ViewerState& s, const CommandLine& c) {
  const Args& a = c.args;
  const double min = parse_number(a[1], "min"), max = parse_number(a[2], "max");
  // Both ends within the parameter values' limit, so the slider's span stays finite.
  check_parameter_value(a[0] + " min", min);
  check_parameter_value(a[0] + " max", max);
  require(s.set_parameter_range(a[0], min, max));
}

void run_clip(ViewerState& s, const CommandLine& c) {
  Clip whole;  // the clip limits of the volume as a whole, as for --clip
  for (const auto& spec : c.args) whole.add(spec);
  whole.check_extent();
  require(s.set_clip_specs(c.args));
}
void run_mode(ViewerState& s, const CommandLine& c) { s.set_mode(parse_mode(c.args[0])); }

void run_play(ViewerState& s, const CommandLine& c) {
  require(s.play(c.args.empty() ? std::string_view{} : std::string_view(c.args[0])));
}

void run_pause(ViewerState& s, const CommandLine&) { s.pause(); }
void run_loop(ViewerState& s, const CommandLine& c) { s.set_loop(parse_on_off(c.args[0], "loop")); }

void run_speed(ViewerState& s, const CommandLine& c) {
  require(s.set_speed(parse_number(c.args[0], "speed")));
}

// KEY=VALUE → (KEY, VALUE); `command` names the command in the message.
std::pair<std::string, std::string> split_key_value(const std::string& kv, const char* command) {
  const size_t eq = kv.find('=');
  if (eq == std::string::npos)
    throw InvalidArgument(fmt::format("{}: expected KEY=VALUE, got '{}'", command, kv));
  return {kv.substr(0, eq), kv.substr(eq + 1)};
}

// A value as the scene file has it: on/off (and the other words parse_on_off takes) for a key
// that is true or false now, and for the mesh's improve (true, false or steps); else a JSON
// number, true or false as written; any other text is a string ("fix", "sparse", "mixed").
// The scene file's reader then checks it with its words.
nlohmann::json setting_value(const std::string& key, const std::string& text,
                             const nlohmann::json& current) {
  if (current.is_boolean() || key == "improve") {
    try {
      return parse_on_off(text, key);
    } catch (const InvalidArgument&) {
    }
  }
  nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_discarded() && (j.is_number() || j.is_boolean() || j.is_string())) return j;
  return text;
}

// KEY=VALUE... as entries of the scene file's `object`; `max_steps` takes the mesh's
// viewer-only key of that name.
nlohmann::json settings_entries(ViewerState& s, const char* object, const Args& args,
                                std::optional<int>* max_steps = nullptr) {
  const nlohmann::json current = s.settings_object(object);
  nlohmann::json entries = nlohmann::json::object();
  for (const auto& kv : args) {
    const auto [key, value] = split_key_value(kv, object);
    if (max_steps && key == "max_steps") {
      // The range is the library's validator's (set_settings).
      constexpr long long kMost = std::numeric_limits<int>::max();
      *max_steps = static_cast<int>(parse_integer(value, key, -kMost, kMost));
      continue;
    }
    entries[key] = setting_value(key, value, current.contains(key) ? current[key] : nullptr);
  }
  return entries;
}

void run_floaters(ViewerState& s, const CommandLine& c) {
  if (c.args.size() == 1 && c.args[0] == "reset") {
    s.reset_floaters();
    return;
  }
  require(s.set_settings("floaters", settings_entries(s, "floaters", c.args), "floaters"));
}

void run_mesh(ViewerState& s, const CommandLine& c) {
  std::optional<int> max_steps;
  const nlohmann::json entries = settings_entries(s, "mesh", c.args, &max_steps);
  require(s.set_settings("mesh", entries, "mesh", max_steps));
}

// set floaters.KEY VALUE | set mesh.KEY VALUE: one key of the scene file's object.
void run_set(ViewerState& s, const CommandLine& c) {
  const std::string& name = c.args[0];
  const size_t dot = name.find('.');
  const std::string object = name.substr(0, dot);
  if (dot == std::string::npos || dot + 1 == name.size() ||
      (object != "floaters" && object != "mesh"))
    throw InvalidArgument("set", name, "expected floaters.KEY or mesh.KEY");
  const std::string key = name.substr(dot + 1);
  const nlohmann::json current = s.settings_object(object);
  const nlohmann::json value =
      setting_value(key, c.args[1], current.contains(key) ? current[key] : nullptr);
  require(s.set_settings(object, {{key, value}}, "set"));
}

void run_draw(ViewerState& s, const CommandLine& c) {
  const std::string& how = c.args[0];
  if (how != "disks" && how != "points")
    throw InvalidArgument("draw", how, "expected disks or points");
  DisplaySettings d = s.display();
  d.draw_points = how == "points";
  require(s.set_display(d));
}

void run_disk_scale(ViewerState& s, const CommandLine& c) {
  DisplaySettings d = s.display();
  d.disk_scale = parse_number(c.args[0], "disk-scale");
  require(s.set_display(d));
}

void run_point_size(ViewerState& s, const CommandLine& c) {
  DisplaySettings d = s.display();
  d.point_size_px = parse_number(c.args[0], "point-size");
  require(s.set_display(d));
}

void run_wireframe(ViewerState& s, const CommandLine& c) {
  DisplaySettings d = s.display();
  d.wireframe = parse_on_off(c.args[0], "wireframe");
  require(s.set_display(d));
}

void run_singular(ViewerState& s, const CommandLine& c) {
  DisplaySettings d = s.display();
  d.show_singular = parse_on_off(c.args[0], "singular");
  require(s.set_display(d));
}

void run_lights(ViewerState& s, const CommandLine& c) {
  const std::string& how = c.args[0];
  if (how != "follow" && how != "fixed")
    throw InvalidArgument("lights", how, "expected follow or fixed");
  s.set_lights_follow_camera(how == "follow");
}

void run_color(ViewerState& s, const CommandLine& c) {
  const Args& a = c.args;
  RenderOptions look = s.look();
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
  require(s.set_look(look));
}

void run_camera(ViewerState& s, const CommandLine& c) {
  const Args& a = c.args;
  Camera cam = s.camera();
  cam.azimuth_deg = parse_number(a[0], "azimuth");
  cam.elevation_deg = parse_number(a[1], "elevation");
  if (a.size() == 3) cam.distance = parse_number(a[2], "distance");
  validate_camera(cam);
  require(s.set_camera(cam));
}

void run_projection(ViewerState& s, const CommandLine& c) {
  const Args& a = c.args;
  Camera cam = s.camera();
  const std::optional<Projection> p = find_projection(a[0]);
  if (!p) throw InvalidArgument("projection", a[0], "expected perspective or orthographic");
  if (a.size() == 2 && *p != Projection::orthographic)
    throw InvalidArgument("projection", a[1], "only an orthographic camera takes a HEIGHT");
  cam.projection = *p;
  if (a.size() == 2) {
    cam.ortho_height = parse_number(a[1], "orthographic height");
    if (!(cam.ortho_height > 0))
      throw InvalidArgument("orthographic height", a[1], "must be positive");
  }
  validate_camera(cam);
  require(s.set_camera(cam));
}

void run_orbit(ViewerState& s, const CommandLine& c) {
  Camera cam = s.camera();
  const double d_az = parse_number(c.args[0], "azimuth change");
  const double d_el = parse_number(c.args[1], "elevation change");
  if (!(std::abs(d_az) <= 360))
    throw InvalidArgument("azimuth change", c.args[0], "must lie in [-360, 360]");
  if (!(std::abs(d_el) <= 180))
    throw InvalidArgument("elevation change", c.args[1], "must lie in [-180, 180]");
  // Kept in (-360, 360): many orbits must not add up to an azimuth validate_camera refuses.
  cam.azimuth_deg = std::fmod(cam.azimuth_deg + d_az, 360.0);
  cam.elevation_deg += d_el;
  require(s.set_camera(cam));
}

void run_zoom(ViewerState& s, const CommandLine& c) {
  const double f = parse_number(c.args[0], "zoom");
  // The distance is clamped to [0.05, 50] scene radii anyway; 1/f must stay finite.
  if (!(f >= 1e-6 && f <= 1e6)) throw InvalidArgument("zoom", c.args[0], "must lie in [1e-6, 1e6]");
  s.zoom(1 / f);
}

void run_pan(ViewerState& s, const CommandLine& c) {
  // In pixels: more than a few screens' width moves the target out of any useful place (and
  // far enough would make it overflow).
  const double dx = parse_number(c.args[0], "dx"), dy = parse_number(c.args[1], "dy");
  for (const auto& [what, v, text] :
       {std::tuple{"dx", dx, c.args[0]}, std::tuple{"dy", dy, c.args[1]}})
    if (!(std::abs(v) <= 1e5)) throw InvalidArgument(what, text, "must lie in [-1e5, 1e5] pixels");
  s.pan(dx, dy);
}

Ease parse_ease_name(const std::string& text) {
  if (const std::optional<Ease> e = find_ease(text)) return *e;
  throw InvalidArgument("ease", text, "expected linear, in, out or in-out");
}

std::size_t parse_keyframe_index(const std::string& text) {
  return static_cast<std::size_t>(parse_integer(text, "keyframe index", 0, 1'000'000'000));
}

void run_keyframe(ViewerState& s, const CommandLine& c) {
  const Args& a = c.args;
  const std::string& what = a[0];
  const auto count = [&](std::size_t lo, std::size_t hi, const char* usage) {
    if (a.size() < lo || a.size() > hi)
      throw InvalidArgument(fmt::format("usage: keyframe {}", usage));
  };
  // The optional ease of add and update, checked before anything changes.
  const auto ease = [&] {
    return a.size() > 2 ? std::optional<Ease>(parse_ease_name(a[2])) : std::nullopt;
  };
  if (what == "add") {
    count(2, 3, "add TIME [EASE]");
    const double time = parse_number(a[1], "keyframe time");
    require(s.add_keyframe(time, ease()));
  } else if (what == "update") {
    count(2, 3, "update INDEX [EASE]");
    const std::size_t index = parse_keyframe_index(a[1]);
    require(s.update_keyframe(index, ease()));
  } else if (what == "ease") {
    count(3, 3, "ease INDEX EASE");
    const std::size_t index = parse_keyframe_index(a[1]);
    require(s.set_keyframe_ease(index, parse_ease_name(a[2])));
  } else if (what == "move") {
    count(3, 3, "move INDEX TIME");
    const std::size_t index = parse_keyframe_index(a[1]);
    require(s.move_keyframe(index, parse_number(a[2], "keyframe time")));
  } else if (what == "delete") {
    count(2, 2, "delete INDEX");
    require(s.delete_keyframe(parse_keyframe_index(a[1])));
  } else if (what == "clear") {
    count(1, 1, "clear");
    s.clear_keyframes();
  } else if (what == "time") {
    count(2, 2, "time T");
    require(s.scrub_keyframes(parse_number(a[1], "keyframe time")));
  } else {
    throw InvalidArgument("keyframe", what,
                          "expected add, update, ease, move, delete, clear or time");
  }
}

void run_reset_view(ViewerState& s, const CommandLine&) { s.reset_view(); }
void run_save_scene(ViewerState& s, const CommandLine& c) { require(s.save_scene(c.args[0])); }
void run_save_mesh(ViewerState& s, const CommandLine& c) { require(s.save_mesh(c.args[0])); }

void run_save_floaters(ViewerState& s, const CommandLine& c) {
  require(s.save_floaters(c.args[0]));
}

void run_save_pov(ViewerState& s, const CommandLine& c) { require(s.save_pov(c.args[0])); }

}  // namespace

const std::vector<CommandInfo>& command_table() {
  static const std::vector<CommandInfo> table = {
      // surface
      {"equation", 1, -1, "equation TEXT", "type an equation (the rest of the line)", run_equation},
      {"catalog", 1, 1, "catalog NAME", "open a catalog surface with its defaults", run_catalog},
      {"load", 1, 1, "load FILE.json", "open a scene file", run_load},
      {"param", 2, 2, "param NAME VALUE", "set a parameter", run_param},
      {"range", 3, 3, "range NAME MIN MAX", "set a parameter's slider range", run_range},
      {"clip", 1, -1, "clip SPEC...", "replace the clip: sphere:R, box:H, plane:nx,ny,nz,d, ...",
       run_clip},
      // modes and animation
      {"mode", 1, 1, "mode floaters|mesh|raytrace", "switch what the view shows", run_mode},
      {"play", 0, 1, "play [NAME]", "animate a parameter through its range", run_play},
      {"pause", 0, 0, "pause", "stop the animation", run_pause},
      {"loop", 1, 1, "loop on|off", "animate back and forth, or stop at the end", run_loop},
      {"speed", 1, 1, "speed RANGES_PER_SECOND", "animation speed (0.1: one sweep in 10 s)",
       run_speed},
      {"floaters", 1, -1, "floaters KEY=VALUE... | floaters reset",
       "keys of the scene file's floaters object: max_count, radius (σ̂, 0 auto), cos_weight, "
       "radius_adapt (wh|curvature|singular|mixed), feedback (φ), equilibrium_speed (γ), ...",
       run_floaters},
      {"mesh", 1, -1, "mesh KEY=VALUE...",
       "keys of the scene file's mesh object: cells, improve (on|off|auto|STEPS), boundary "
       "(fix|constrain), grid, curvature_weight (κ_d), ...; and max_steps",
       run_mesh},
      {"set", 2, 2, "set floaters.KEY|mesh.KEY VALUE",
       "one setting by its scene file key, checked as in scene files", run_set},
      {"draw", 1, 1, "draw disks|points", "how floaters are drawn", run_draw},
      {"disk-scale", 1, 1, "disk-scale S", "disk radius as a multiple of the floater radius",
       run_disk_scale},
      {"point-size", 1, 1, "point-size PIXELS", "size of floaters drawn as points", run_point_size},
      {"wireframe", 1, 1, "wireframe on|off", "overlay the mesh edges", run_wireframe},
      {"singular", 1, 1, "singular on|off",
       "overlay the singular set: curves as tubes, special points as spheres", run_singular},
      {"lights", 1, 1, "lights follow|fixed", "lights follow the camera, or stay in the world",
       run_lights},
      {"color", 4, 4, "color front|back|background R G B", "a colour (components in [0, 1])",
       run_color},
      {"keyframe", 1, 3,
       "keyframe add TIME [EASE] | update I [EASE] | ease I EASE | move I TIME | delete I | "
       "clear | time T",
       "record keyframes of the parameters and camera (TIME in [0, 1], EASE linear|in|out|in-out; "
       "time T shows the animation at T)",
       run_keyframe},
      // camera
      {"camera", 2, 3, "camera AZIMUTH ELEVATION [DISTANCE]", "set the orbit camera (degrees)",
       run_camera},
      {"projection", 1, 2, "projection perspective|orthographic [HEIGHT]",
       "pinhole or parallel rays (HEIGHT > 0: the window's height in world units; omitted: "
       "the camera's own)",
       run_projection},
      {"orbit", 2, 2, "orbit D_AZIMUTH D_ELEVATION", "turn the camera (degrees)", run_orbit},
      {"zoom", 1, 1, "zoom FACTOR", "come closer by FACTOR (< 1 moves away)", run_zoom},
      {"pan", 2, 2, "pan DX DY", "move the picture by pixels", run_pan},
      {"reset-view", 0, 0, "reset-view", "back to the surface's camera", run_reset_view},
      // files
      {"save-scene", 1, 1, "save-scene FILE.json", "surface, camera and settings", run_save_scene},
      {"save-mesh", 1, 1, "save-mesh FILE.ply|obj|stl", "the current mesh (mesh mode)",
       run_save_mesh},
      {"save-floaters", 1, 1, "save-floaters FILE.ply", "the current floaters (floaters mode)",
       run_save_floaters},
      {"save-pov", 1, 1, "save-pov FILE.pov", "the view as a POV-Ray scene", run_save_pov},
      // frame loop
      {"frames", 1, 1, "frames N", "run N frames"},
      {"wait", 0, 1, "wait [SECONDS]",
       "run frames until the mode's work is done (default: at most 60 s)"},
      {"steps", 1, 2, "steps N [SECONDS]",
       "run frames until the floaters took N more steps (and the singular set, if shown, is "
       "found)"},
      {"sleep", 1, 1, "sleep SECONDS", "run frames for this long"},
      {"screenshot", 1, 1, "screenshot FILE.png", "save the next frame"},
      {"ui", 1, 1, "ui on|off", "show or hide the panel"},
      {"stats", 0, 0, "stats", "print the live statistics as one JSON line"},
      {"expect-error", 0, -1, "expect-error [TEXT]",
       "the previous command must have failed (with TEXT in its message)"},
      {"quit", 0, 0, "quit", "close the viewer"},
  };
  return table;
}

const CommandInfo* find_command(std::string_view name) {
  for (const auto& c : command_table())
    if (c.name == name) return &c;
  return nullptr;
}

CommandLine split_command(std::string_view line) {
  CommandLine out;
  auto is_blank = [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; };
  size_t i = 0;
  while (i < line.size() && is_blank(line[i])) ++i;
  if (i == line.size() || line[i] == '#') return out;
  const size_t name_end = std::find_if(line.begin() + i, line.end(), is_blank) - line.begin();
  out.name = std::string(line.substr(i, name_end - i));
  std::string_view rest = line.substr(name_end);
  while (!rest.empty() && is_blank(rest.front())) rest.remove_prefix(1);
  while (!rest.empty() && is_blank(rest.back())) rest.remove_suffix(1);
  out.rest = std::string(rest);
  size_t j = 0;
  while (j < rest.size()) {
    while (j < rest.size() && is_blank(rest[j])) ++j;
    const size_t k = std::find_if(rest.begin() + j, rest.end(), is_blank) - rest.begin();
    if (k > j) out.args.emplace_back(rest.substr(j, k - j));
    j = k;
  }
  return out;
}

const CommandInfo& check_command(const CommandLine& command) {
  const CommandInfo* info = find_command(command.name);
  if (!info) {
    std::string names;
    for (const auto& c : command_table())
      names += (names.empty() ? "" : ", ") + std::string(c.name);
    throw InvalidArgument(fmt::format("unknown command '{}' (commands: {})", command.name, names));
  }
  const int n = static_cast<int>(command.args.size());
  if (n < info->min_args || (info->max_args >= 0 && n > info->max_args))
    throw InvalidArgument(fmt::format(
        "'{}' takes {}: usage: {}", command.name,
        info->min_args == info->max_args ? fmt::format("{} argument(s)", info->min_args)
        : info->max_args < 0             ? fmt::format("at least {} argument(s)", info->min_args)
                             : fmt::format("{} to {} arguments", info->min_args, info->max_args),
        info->usage));
  return *info;
}

bool parse_on_off(std::string_view text, std::string_view what) {
  if (text == "on" || text == "true" || text == "yes" || text == "1") return true;
  if (text == "off" || text == "false" || text == "no" || text == "0") return false;
  throw InvalidArgument(std::string(what), std::string(text), "expected on or off");
}

double parse_number(std::string_view text, std::string_view what) {
  double v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size())
    throw InvalidArgument(std::string(what), std::string(text), "not a number");
  if (!std::isfinite(v))
    throw InvalidArgument(std::string(what), std::string(text), "must be finite");
  return v;
}

long long parse_integer(std::string_view text, std::string_view what, long long lo, long long hi) {
  long long v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size())
    throw InvalidArgument(std::string(what), std::string(text), "not a whole number");
  if (v < lo || v > hi)
    throw InvalidArgument(std::string(what), std::string(text),
                          fmt::format("must lie in [{}, {}]", lo, hi));
  return v;
}

}  // namespace zeroset::viewer
