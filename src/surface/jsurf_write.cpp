// Writing SURFER's .jsurf files (zeroset/surface/jsurf.h); the reader is jsurf.cpp.
#include <fmt/core.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

#include "jsurf_detail.h"
#include "properties_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/surface/jsurf.h"

namespace zeroset {
namespace {

using json = nlohmann::json;

using detail::kJsurfGamma;
using detail::kJsurfLights;

bool is_identifier_start(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool is_identifier_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// The parameters' names in SURFER: a..d keep theirs, the others take the free letters in order.
std::map<std::string, std::string> surfer_names(const std::vector<std::string>& names) {
  if (names.size() > static_cast<size_t>(kMaxJsurfParameters)) {
    std::string list;
    for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
    throw BadInput(
        fmt::format("SURFER has at most {} parameters (a, b, c, d); this surface has "
                    "{}: {}",
                    kMaxJsurfParameters, names.size(), list));
  }
  std::map<std::string, std::string> out;
  std::string free = "abcd";
  for (const auto& n : names)
    if (n.size() == 1 && free.find(n) != std::string::npos) {
      out[n] = n;
      free.erase(free.find(n), 1);
    }
  size_t next = 0;
  for (const auto& n : names)
    if (!out.count(n)) out[n] = std::string(1, free[next++]);
  return out;
}

// The equation in SURFER's syntax: numbers, x y z, parameters, + - * / ^, parentheses and
// function calls. The expression comes with definitions substituted; pi and e become numbers.
std::string surfer_equation(const Field& field, const std::map<std::string, std::string>& names) {
  const std::string text = field.expression_string();
  std::string out;
  for (size_t i = 0; i < text.size();) {
    const char c = text[i];
    if (is_identifier_start(c)) {
      size_t j = i;
      while (j < text.size() && is_identifier_char(text[j])) ++j;
      const std::string word = text.substr(i, j - i);
      if (const auto it = names.find(word); it != names.end())
        out += it->second;
      else if (word == "pi")
        out += fmt::format("{}", M_PI);
      else if (word == "e" && (j >= text.size() || text[j] != '('))
        out += fmt::format("{}", M_E);
      else
        out += word;  // x, y, z, or a function name
      i = j;
    } else if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      size_t j = i;
      while (j < text.size() &&
             (std::isdigit(static_cast<unsigned char>(text[j])) || text[j] == '.' ||
              ((text[j] == 'e' || text[j] == 'E') && j + 1 < text.size()) ||
              ((text[j] == '+' || text[j] == '-') && (text[j - 1] == 'e' || text[j - 1] == 'E'))))
        ++j;
      out += text.substr(i, j - i);
      i = j;
    } else if (c == '*' && i + 1 < text.size() && text[i + 1] == '*') {
      out += '^';
      i += 2;
    } else if (std::string_view("+-*/^() ").find(c) != std::string_view::npos) {
      out += c;
      ++i;
    } else {
      throw BadInput(
          fmt::format("the equation cannot be written in SURFER's syntax (it uses "
                      "'{}'): {}",
                      c, text));
    }
  }
  return out;
}

Vec3 display(const json& j, const std::string& what) {
  if (j.is_string()) {  // "#rrggbb": a display value already
    const std::string s = j.get<std::string>();
    unsigned r = 0, g = 0, b = 0;
    if (s.size() == 7 && s[0] == '#' && std::sscanf(s.c_str() + 1, "%2x%2x%2x", &r, &g, &b) == 3)
      return Vec3(r, g, b) / 255.0;
  } else if (j.is_array() && j.size() == 3 && j[0].is_number() && j[1].is_number() &&
             j[2].is_number()) {
    const Vec3 linear(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
    return linear.cwiseMax(Vec3::Zero()).array().pow(1 / kJsurfGamma).matrix();
  }
  throw BadInput(fmt::format("render/{}: expected '#rrggbb' or [r, g, b]", what));
}

// A number of the file; SURFER cannot read nan or inf, so a scene with one is refused.
std::string finite_number(double x) {
  if (!std::isfinite(x))
    throw BadInput(fmt::format("SURFER export: a number of the scene is not finite ({})", x));
  return fmt::format("{}", x);
}

std::string numbers(std::initializer_list<double> v) {
  std::string out;
  for (double x : v) {
    if (!out.empty()) out += ' ';
    out += finite_number(x);
  }
  return out;
}
std::string numbers(const Vec3& v) { return numbers({v.x(), v.y(), v.z()}); }

}  // namespace

std::string scene_to_jsurf(const Scene& scene) {
  const Surface& s = scene.surface;
  const Field& field = s.field;
  const auto names = surfer_names(field.parameter_names());
  if (!field.is_polynomial())
    throw BadInput("SURFER draws algebraic surfaces only, and F is not a polynomial in x, y, z");
  // A coefficient that is not finite at the scene's parameter values (x/0) is no surface SURFER
  // can draw, as POV-Ray's export refuses it too.
  if (field.is_expandable()) {
    const Polynomial expanded = field.polynomial();
    for (const Monomial& m : expanded.terms())
      if (!std::isfinite(m.c))
        throw BadInput(
            fmt::format("SURFER export: a coefficient of '{}' is not finite ({}) at "
                        "the scene's parameter values",
                        field.source(), m.c));
  }
  const std::string equation = surfer_equation(field, names);
  const ParseResult check = parse_field(equation);  // the text must mean the same surface
  if (!check.ok() || check.field->parameter_names().size() != names.size())
    throw Error("the equation could not be rewritten for SURFER:\n" + equation);

  if (!s.clip.planes.empty() || s.clip.spheres.size() != 1) {
    std::string specs;
    for (const auto& spec : s.clip.to_specs()) specs += (specs.empty() ? "" : " ") + spec;
    throw BadInput(
        fmt::format("SURFER clips to one sphere about the origin; this clip is {} "
                    "(give one with --clip sphere:R)",
                    specs.empty() ? "empty (all of space)" : specs));
  }
  const SphereClip& sphere = s.clip.spheres[0];
  if (sphere.center.norm() != 0)
    throw BadInput("SURFER clips to a sphere about the origin; this one is centred elsewhere");
  const double radius = sphere.radius;

  // jsurf's transforms (see jsurf.cpp): rotation_matrix has the camera's right, up and back
  // directions as columns, camera_transform moves the eye into place in clipping space (units
  // of the clip radius), so surface = radius · rotation · (camera point − t).
  const CameraFrame f = s.camera.frame(s.scene_radius());
  Mat3 rot;
  rot.col(0) = f.right;
  rot.col(1) = f.up;
  rot.col(2) = -f.forward;
  const Vec3 t = -rot.transpose() * f.eye / radius;

  std::string out = "# SURFER scene (.jsurf) written by zeroset\n";
  auto put = [&](const std::string& key, const std::string& value) {
    out += detail::escape_property(key, true) + "=" + detail::escape_property(value) + "\n";
  };
  put("surface_equation", equation);
  const auto& values = field.parameter_values();
  for (size_t i = 0; i < field.parameter_names().size(); ++i)
    put("surface_parameter_" + names.at(field.parameter_names()[i]), finite_number(values[i]));
  put("scale_factor", finite_number(std::log10(radius)));
  put("rotation_matrix", numbers({rot(0, 0), rot(0, 1), rot(0, 2), 0, rot(1, 0), rot(1, 1),
                                  rot(1, 2), 0, rot(2, 0), rot(2, 1), rot(2, 2), 0, 0, 0, 0, 1}));
  if (s.camera.is_orthographic()) {
    put("camera_type", "ORTHOGRAPHIC_CAMERA");
    put("camera_height", finite_number(s.camera.view_height(s.scene_radius()) / radius));
  } else {
    put("camera_type", "PERSPECTIVE_CAMERA");
  }
  put("camera_fov_y", finite_number(s.camera.fov_deg));
  put("camera_transform", numbers({1, 0, 0, t.x(), 0, 1, 0, t.y(), 0, 0, 1, t.z(), 0, 0, 0, 1}));

  const json render = scene.settings.is_object() && scene.settings.contains("render")
                          ? scene.settings["render"]
                          : json::object();
  if (render.contains("background"))
    put("background_color", numbers(display(render["background"], "background")));
  for (const char* side : {"front", "back"}) {
    if (!render.contains(side) || !render[side].is_object()) continue;
    const json& m = render[side];
    const std::string p = std::string(side) + "_material_";
    auto number = [&](const char* key) {
      if (!m[key].is_number())
        throw BadInput(fmt::format("render/{}/{}: expected a number", side, key));
      return finite_number(m[key].get<double>());
    };
    if (m.contains("diffuse")) {
      put(p + "color", numbers(display(m["diffuse"], std::string(side) + "/diffuse")));
      put(p + "diffuse_intensity", "1");  // zeroset's diffuse strength is the colour itself
    }
    if (m.contains("ambient")) put(p + "ambient_intensity", number("ambient"));
    if (m.contains("specular")) put(p + "specular_intensity", number("specular"));
    if (m.contains("shininess")) put(p + "shininess", number("shininess"));
  }
  if (render.contains("lights") && render["lights"].is_array()) {
    const json& lights = render["lights"];
    if (lights.size() > static_cast<size_t>(kJsurfLights))
      throw BadInput(
          fmt::format("SURFER has {} lights; this scene has {}", kJsurfLights, lights.size()));
    // Far from the clip sphere's centre (t in camera space), so that jsurf's point lights
    // shine from nearly one direction, as zeroset's do.
    const double far = 100 * (t.norm() + 1);
    for (size_t i = 0; i < lights.size(); ++i) {
      const json& l = lights[i];
      const json& d = l.value("direction", json());
      if (!d.is_array() || d.size() != 3 || !d[0].is_number() || !d[1].is_number() ||
          !d[2].is_number())
        throw BadInput(fmt::format("render/lights/{}/direction: expected [x, y, z]", i));
      Vec3 dir(d[0].get<double>(), d[1].get<double>(), d[2].get<double>());
      if (!l.value("follows_camera", true)) dir = rot.transpose() * dir;  // world -> camera
      if (!(dir.norm() > 0) || !dir.allFinite()) continue;  // shines nowhere, as in zeroset
      const Vec3 color = l.contains("color")
                             ? display(l["color"], fmt::format("lights/{}/color", i))
                             : Vec3(1, 1, 1);
      put(fmt::format("light_status_{}", i), "ON");
      put(fmt::format("light_position_{}", i), numbers(Vec3(t + far * dir.normalized())));
      put(fmt::format("light_color_{}", i), numbers(color));
      put(fmt::format("light_intensity_{}", i), "1");
    }
  }
  return out;
}

void write_jsurf(const Scene& scene, const std::string& path) {
  const std::string text = scene_to_jsurf(scene);
  write_file_atomically(path, [&](std::ostream& o) { o << text; });
}

}  // namespace zeroset
