#include "zeroset/surface/keyframes.h"

#include <fmt/core.h>

#include <algorithm>

#include "zeroset/error.h"
#include "zeroset/surface/json_read.h"
#include "zeroset/surface/settings.h"

namespace zeroset {
namespace {

using json = nlohmann::json;
using json_read::fail;
using json_read::number;

double* camera_field(Camera& c, const std::string& name) {
  if (name == "azimuth_deg") return &c.azimuth_deg;
  if (name == "elevation_deg") return &c.elevation_deg;
  if (name == "distance") return &c.distance;
  if (name == "roll_deg") return &c.roll_deg;
  if (name == "fov_deg") return &c.fov_deg;
  if (name == "ortho_height") return &c.ortho_height;
  return nullptr;
}

KeyTrack& track_of(std::vector<KeyTrack>& tracks, const std::string& name) {
  for (KeyTrack& t : tracks)
    if (t.name == name) return t;
  KeyTrack t;
  t.name = name;
  tracks.push_back(std::move(t));
  return tracks.back();
}

Ease ease_from(const json& j, const std::string& origin, const std::string& where) {
  if (const std::optional<Ease> e = find_ease(json_read::string(j, origin, where))) return *e;
  fail(origin, where, "expected \"linear\", \"in\", \"out\" or \"in-out\"");
}

}  // namespace

double ease(Ease e, double s) {
  switch (e) {
    case Ease::kLinear:
      return s;
    case Ease::kIn:
      return s * s;
    case Ease::kOut:
      return 1 - (1 - s) * (1 - s);
    case Ease::kInOut:
      return s * s * (3 - 2 * s);
  }
  return s;
}

const char* ease_name(Ease e) {
  switch (e) {
    case Ease::kLinear:
      return "linear";
    case Ease::kIn:
      return "in";
    case Ease::kOut:
      return "out";
    case Ease::kInOut:
      return "in-out";
  }
  return "linear";
}

std::optional<Ease> find_ease(std::string_view name) {
  for (Ease e : {Ease::kLinear, Ease::kIn, Ease::kOut, Ease::kInOut})
    if (name == ease_name(e)) return e;
  return std::nullopt;
}

double KeyTrack::value(double time) const {
  if (time <= times.front()) return values.front();
  for (size_t i = 0; i + 1 < times.size(); ++i)
    if (time <= times[i + 1]) {
      const double s = (time - times[i]) / (times[i + 1] - times[i]);
      return values[i] + ease(eases[i], s) * (values[i + 1] - values[i]);
    }
  return values.back();
}

const KeyTrack* Keyframes::param(const std::string& name) const {
  for (const KeyTrack& t : params)
    if (t.name == name) return &t;
  return nullptr;
}

Surface Keyframes::at(Surface surface, double time) const {
  for (const KeyTrack& t : params) surface.field.set_parameter(t.name, t.value(time));
  surface.clip.update(surface.field);  // a clip that follows the parameters
  for (const KeyTrack& t : camera) *camera_field(surface.camera, t.name) = t.value(time);
  if (!projections.empty()) {
    surface.camera.projection = projections.front().second;
    for (const auto& [at, projection] : projections)
      if (at <= time) surface.camera.projection = projection;
  }
  return surface;
}

double frame_time(int frame, int frames) {
  return frames <= 1 ? 0.0 : static_cast<double>(frame) / (frames - 1);
}

const std::vector<std::string>& keyframe_camera_fields() {
  static const std::vector<std::string> fields = {"azimuth_deg", "elevation_deg", "distance",
                                                  "roll_deg",    "fov_deg",       "ortho_height"};
  return fields;
}

Keyframes read_keyframes(const json& settings, const Surface& surface, int frames,
                         const std::string& origin) {
  Keyframes out;
  if (!settings.is_object() || !settings.contains("animation")) return out;
  const json& animation = settings["animation"];
  if (!animation.is_object() || !animation.contains("keyframes")) return out;
  const json& keys = animation["keyframes"];
  const std::string base = "/animation/keyframes";
  if (!keys.is_array() || keys.empty())
    fail(origin, base,
         "expected a list of keyframes {\"time\" or \"frame\", \"params\", "
         "\"camera\", \"ease\"}");
  double last_time = -1;
  for (size_t i = 0; i < keys.size(); ++i) {
    const json& k = keys[i];
    const std::string where = fmt::format("{}/{}", base, i);
    if (!k.is_object()) fail(origin, where, "expected an object");
    json_read::known_keys(k, {"time", "frame", "params", "camera", "ease"}, origin, where);
    if (k.contains("time") == k.contains("frame"))
      fail(origin, where, "give either \"time\" (0 to 1) or \"frame\" (0 to frames - 1)");
    const double time =
        k.contains("time")
            ? json_read::number_in(k["time"], origin, where + "/time", 0, 1)
            : frame_time(static_cast<int>(json_read::whole(k["frame"], origin, where + "/frame", 0,
                                                           std::max(0, frames - 1))),
                         frames);
    if (!(time > last_time))
      fail(origin, where,
           fmt::format("keyframes must come in increasing time; this one is at "
                       "time {}, the one before at {}",
                       time, last_time));
    last_time = time;
    const Ease e =
        k.contains("ease") ? ease_from(k["ease"], origin, where + "/ease") : Ease::kInOut;
    const auto add = [&](std::vector<KeyTrack>& tracks, const std::string& name, double v) {
      KeyTrack& t = track_of(tracks, name);
      t.times.push_back(time);
      t.values.push_back(v);
      t.eases.push_back(e);
    };
    if (k.contains("params")) {
      const json& ps = k["params"];
      if (!ps.is_object()) fail(origin, where + "/params", "expected an object {name: value}");
      for (const auto& [name, v] : ps.items()) {
        const std::string at = where + "/params/" + json_read::pointer_token(name);
        if (surface.field.parameter_index(name) < 0)
          fail(origin, at, "the surface has no parameter '" + name + "'");
        const double value = number(v, origin, at);
        try {
          check_parameter_value(name, value);
        } catch (const InvalidArgument& e) {
          fail(origin, at, e.what());
        }
        add(out.params, name, value);
      }
    }
    if (k.contains("camera")) {
      const json& c = k["camera"];
      if (!c.is_object()) fail(origin, where + "/camera", "expected an object");
      json_read::known_keys(c,
                            {"azimuth_deg", "elevation_deg", "distance", "roll_deg", "fov_deg",
                             "ortho_height", "projection"},
                            origin, where + "/camera");
      for (const auto& [name, v] : c.items()) {
        const std::string at = where + "/camera/" + name;
        if (name == "projection") {
          const std::optional<Projection> p = find_projection(json_read::string(v, origin, at));
          if (!p) fail(origin, at, "expected \"perspective\" or \"orthographic\"");
          out.projections.emplace_back(time, *p);
          continue;
        }
        Camera probe = surface.camera;
        *camera_field(probe, name) = number(v, origin, at);
        // 0 fits the clip in a scene's camera; between two keyframes it would mean nothing.
        if (name == "distance" && !(probe.distance > 0))
          fail(origin, at, "a keyframe's distance must be positive");
        if (name == "ortho_height" && !(probe.ortho_height > 0))
          fail(origin, at, "a keyframe's ortho_height must be positive");
        try {
          validate_camera(probe);
        } catch (const SettingError& err) {
          fail(origin, at, err.why());
        }
        // Each field's valid values form an interval, and eased values stay between the
        // keyframes', so every frame's camera is valid too.
        add(out.camera, name, *camera_field(probe, name));
      }
    }
  }
  return out;
}

}  // namespace zeroset
