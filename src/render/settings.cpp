#include "zeroset/render/settings.h"

#include <fmt/core.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "zeroset/error.h"
#include "zeroset/surface/json_read.h"

namespace zeroset {
namespace {

using nlohmann::json;

using json_read::fail;
using json_read::number;
using json_read::vec3;

void check(bool ok, const std::string& key, const std::string& value, const std::string& why) {
  if (!ok) throw SettingError(key, value, why);
}

std::string text(const Vec3& v) { return fmt::format("[{}, {}, {}]", v.x(), v.y(), v.z()); }

void check_color(const Color& c, const std::string& key) {
  check(c.allFinite() && (c.array() >= 0).all() && (c.array() <= 1).all(), key, text(c),
        "components must lie in [0, 1]");
}

void check_material(const Material& m, const std::string& key) {
  check_color(m.diffuse, key + "/diffuse");
  check(m.ambient >= 0 && m.ambient <= 1, key + "/ambient", fmt::format("{}", m.ambient),
        "must lie in [0, 1]");
  check(m.specular >= 0 && m.specular <= 10, key + "/specular", fmt::format("{}", m.specular),
        "must lie in [0, 10]");
  check(m.shininess >= 0 && m.shininess <= 10000, key + "/shininess",
        fmt::format("{}", m.shininess), "must lie in [0, 10000]");
}

Color color(const json& j, const std::string& origin, const std::string& path) {
  if (j.is_string()) {
    try {
      return parse_display_color(j.get<std::string>(), path);
    } catch (const InvalidArgument&) {
      fail(origin, path, "expected '#rrggbb' or [r, g, b]");
    }
  }
  if (!j.is_array()) fail(origin, path, "expected '#rrggbb' or [r, g, b]");
  return vec3(j, origin, path);  // its range is checked by validate_settings
}

void material(const json& j, Material& m, const std::string& origin, const std::string& path) {
  if (!j.is_object()) fail(origin, path, "expected an object");
  for (const auto& [key, value] : j.items()) {
    const std::string p = path + "/" + key;
    if (key == "diffuse")
      m.diffuse = color(value, origin, p);
    else if (key == "ambient")
      m.ambient = number(value, origin, p);
    else if (key == "specular")
      m.specular = number(value, origin, p);
    else if (key == "shininess")
      m.shininess = number(value, origin, p);
    else
      fail(origin, p, "unknown key (known: diffuse, ambient, specular, shininess)");
  }
}

json color_json(const Color& c) { return {c.x(), c.y(), c.z()}; }

json material_json(const Material& m) {
  return {{"diffuse", color_json(m.diffuse)},
          {"ambient", m.ambient},
          {"specular", m.specular},
          {"shininess", m.shininess}};
}

}  // namespace

void validate_image_size(long long width, long long height) {
  check(width >= 1 && height >= 1 && width <= kMaxImageSide && height <= kMaxImageSide, "size",
        fmt::format("{}x{}", width, height),
        fmt::format("width and height must lie in [1, {}]", kMaxImageSide));
  check(static_cast<double>(width) * static_cast<double>(height) <= kMaxImagePixels, "size",
        fmt::format("{}x{}", width, height),
        fmt::format("must have at most {:.0f} pixels", kMaxImagePixels));
}

void validate_settings(const RenderOptions& o) {
  validate_image_size(o.width, o.height);
  check(o.samples >= 1 && o.samples <= kMaxSamples, "samples", std::to_string(o.samples),
        fmt::format("must lie in [1, {}]", kMaxSamples));
  check_color(o.background, "background");
  check_material(o.front, "front");
  check_material(o.back, "back");
  for (size_t i = 0; i < o.lights.size(); ++i) {
    const std::string key = "lights/" + std::to_string(i);
    const Light& l = o.lights[i];
    // Its length finite and not zero too: (1e300, 0, 0) would normalise to zero.
    const double len = l.direction.norm();
    check(l.direction.allFinite() && len > 0 && std::isfinite(len), key + "/direction",
          text(l.direction), "must be finite and not zero");
    check_color(l.color, key + "/color");
  }
}

Color parse_display_color(const std::string& text, const std::string& what) {
  Color display;
  if (!text.empty() && text[0] == '#') {
    unsigned r = 0, g = 0, b = 0;
    char extra = 0;
    if (text.size() != 7 || std::sscanf(text.c_str(), "#%2x%2x%2x%c", &r, &g, &b, &extra) != 3)
      throw InvalidArgument(what, text, "expected #rrggbb, e.g. #ffffff");
    display = Color(r, g, b) / 255.0;
  } else {
    std::vector<double> v;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) {
      char* end = nullptr;
      const double d = std::strtod(item.c_str(), &end);
      if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(d))
        throw InvalidArgument(what, text, "'" + item + "' is not a finite number");
      v.push_back(d);
    }
    if (v.size() != 3) throw InvalidArgument(what, text, "expected #rrggbb or r,g,b");
    display = Color(v[0], v[1], v[2]);
    if ((display.array() < 0).any() || (display.array() > 1).any())
      throw InvalidArgument(what, text, "components must lie in [0, 1]");
  }
  // Pictures are gamma encoded (Image::set_linear); shading works on linear values.
  return display.array().pow(2.2).matrix();
}

void apply_render_settings(const json& render, RenderOptions& options, const std::string& origin) {
  if (!render.is_object()) fail(origin, "/render", "expected an object");
  RenderOptions o = options;
  for (const auto& [key, value] : render.items()) {
    const std::string p = "/render/" + key;
    if (key == "size") {
      if (!value.is_array() || value.size() != 2 || !value[0].is_number_integer() ||
          !value[1].is_number_integer())
        fail(origin, p, "expected [width, height]");
      const long long w = value[0].get<long long>(), h = value[1].get<long long>();
      try {
        validate_image_size(w, h);  // before narrowing to int
      } catch (const SettingError& e) {
        fail(origin, p, e.why());
      }
      o.width = static_cast<int>(w);
      o.height = static_cast<int>(h);
    } else if (key == "samples") {
      o.samples = static_cast<int>(json_read::whole(value, origin, p, 0, 1e9));
    } else if (key == "background") {
      o.background = color(value, origin, p);
    } else if (key == "front") {
      material(value, o.front, origin, p);
    } else if (key == "back") {
      material(value, o.back, origin, p);
    } else if (key == "lights") {
      if (!value.is_array()) fail(origin, p, "expected an array of lights");
      std::vector<Light> lights;
      for (size_t i = 0; i < value.size(); ++i) {
        const std::string lp = p + "/" + std::to_string(i);
        const json& l = value[i];
        if (!l.is_object()) fail(origin, lp, "expected an object");
        Light light;
        for (const auto& [lk, lv] : l.items()) {
          if (lk == "direction") {
            light.direction = vec3(lv, origin, lp + "/direction");
          } else if (lk == "color") {
            light.color = color(lv, origin, lp + "/color");
          } else if (lk == "follows_camera") {
            light.follows_camera = json_read::boolean(lv, origin, lp + "/follows_camera");
          } else {
            fail(origin, lp + "/" + lk, "unknown key (known: direction, color, follows_camera)");
          }
        }
        lights.push_back(light);
      }
      o.lights = lights;
    } else {
      fail(origin, p, "unknown key (known: size, samples, background, front, back, lights)");
    }
  }
  try {
    validate_settings(o);
  } catch (const SettingError& e) {
    fail(origin, "/render/" + e.key(), e.why());
  }
  options = o;
}

json render_settings_to_json(const RenderOptions& o) {
  json j = {{"size", {o.width, o.height}},
            {"samples", o.samples},
            {"background", color_json(o.background)},
            {"front", material_json(o.front)},
            {"back", material_json(o.back)}};
  if (!o.lights.empty()) {
    json lights = json::array();
    for (const Light& l : o.lights)
      lights.push_back({{"direction", {l.direction.x(), l.direction.y(), l.direction.z()}},
                        {"color", color_json(l.color)},
                        {"follows_camera", l.follows_camera}});
    j["lights"] = lights;
  }
  return j;
}

}  // namespace zeroset
