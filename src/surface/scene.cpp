#include "zeroset/surface/scene.h"

#include <fmt/core.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <limits>
#include <set>
#include <string_view>

#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/json_read.h"
#include "zeroset/surface/jsurf.h"
#include "zeroset/surface/settings.h"

namespace zeroset {
namespace {

using json = nlohmann::json;

using json_read::fail;
using json_read::known_keys;
using json_read::number;
using json_read::vec3;

// An identifier (letters, digits, '_'; not a coordinate): what catalog names look like. Anything
// with an operator, even x-x, is an equation.
bool is_bare_name(const std::string& s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
  return s != "x" && s != "y" && s != "z";
}

// Identifiers joined by '-' ("dupin-cyclide"): an equation, but perhaps meant as a name.
bool is_hyphenated_name(const std::string& s) {
  if (s.find('-') == std::string::npos) return false;
  size_t start = 0;
  while (start <= s.size()) {
    size_t dash = s.find('-', start);
    if (dash == std::string::npos) dash = s.size();
    const std::string part = s.substr(start, dash - start);
    if (part.empty() || !(std::isalpha(static_cast<unsigned char>(part[0])) || part[0] == '_'))
      return false;
    for (char c : part)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_')) return false;
    start = dash + 1;
  }
  return true;
}

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] != b[j - 1])});
      diag = up;
    }
  }
  return row[b.size()];
}

std::string suggestion(const std::string& name) {
  const CatalogEntry* best = nullptr;
  size_t best_d = 3;  // suggest only close misspellings
  for (const auto& e : catalog()) {
    const size_t d = edit_distance(name, e.name);
    if (d < best_d) {
      best_d = d;
      best = &e;
    }
  }
  return best ? fmt::format(" (did you mean '{}'?)", best->name) : "";
}

// A clip for a typed equation that comes without one: when F is a polynomial whose
// highest-degree part H_d keeps one sign on the unit sphere, the surface is bounded, since
// |F(R u)| ≥ m R^d - Σ_{k<d} |H_k|₁ R^k > 0 for R large (m = min |H_d| on the sphere, |H_k|₁ the
// sum of the absolute coefficients of degree k). m is estimated on 4,000 directions and the
// axes and halved for safety; forms that come near zero anywhere are treated as indefinite. Returns
// an empty clip when no bound is found (an unbounded surface).
Clip default_clip(const Field& field) {
  if (!field.is_expandable() || !field.missing_parameters().empty()) return {};
  const Polynomial poly = field.polynomial();
  const int d = poly.degree();
  if (d < 2 || d % 2) return {};
  std::vector<double> l1(d, 0.0);
  std::vector<Monomial> top;
  for (const Monomial& m : poly.terms()) {
    if (m.degree() == d)
      top.push_back(m);
    else
      l1[m.degree()] += std::abs(m.c);
  }
  const Polynomial lead(top);
  const int n = 4000;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int i = 0; i < n; ++i) {  // Fibonacci sphere
    const double zc = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - zc * zc);
    const double ph = i * M_PI * (3 - std::sqrt(5.0));
    const double v = lead.value(Vec3(r * std::cos(ph), r * std::sin(ph), zc));
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  for (int k = 0; k < 3; ++k)  // the axes, where semidefinite forms such as x²+y² vanish
    for (double sgn : {-1.0, 1.0}) {
      Vec3 u = Vec3::Zero();
      u[k] = sgn;
      const double v = lead.value(u);
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  if (!(lo > 0 || hi < 0)) return {};
  // A form that nearly vanishes in some sampled direction may vanish between samples
  // (semidefinite): then no bound is claimed.
  const double small = std::min(std::abs(lo), std::abs(hi)),
               big = std::max(std::abs(lo), std::abs(hi));
  if (small < 0.02 * big) return {};
  const double m = 0.5 * small;
  auto separated = [&](double R) {
    double rest = 0;
    for (int k = 0; k < d; ++k) rest += l1[k] * std::pow(R, k);
    return m * std::pow(R, d) > rest;
  };
  // The sphere stays within kMaxClipCoordinate, so a saved scene can be read again.
  const double largest = kMaxClipCoordinate / 1.1;
  double R = 1e-3;
  while (!separated(R) && R < largest) R *= 1.05;
  if (R >= largest) return {};
  return Clip::sphere(1.1 * R);
}

}  // namespace

Surface surface_from_equation(const std::string& equation) {
  Surface s;
  s.field = compile_field(equation);
  for (const auto& name : s.field.parameter_names()) s.ranges.push_back({name, 0, 1});
  return s;
}

namespace {

void apply_overrides(Scene& scene, const SurfaceOverrides& o) {
  Surface& s = scene.surface;
  for (const auto& [name, value] : o.params) {
    if (s.field.parameter_index(name) < 0) {
      std::string have;
      for (const auto& n : s.field.parameter_names()) have += (have.empty() ? "" : ", ") + n;
      throw InvalidArgument(
          fmt::format("--param {}: the surface has no parameter '{}'{}", name, name,
                      have.empty() ? " (it has none)" : fmt::format(" (it has: {})", have)));
    }
    s.field.set_parameter(name, value);
  }
  if (!o.clip_specs.empty()) {
    Clip c;
    for (const auto& spec : o.clip_specs) c.add(spec);
    s.clip = c;
  }
  // A parametric clip (given here or by the scene) at the final parameter values; checks the
  // extent of every clip given here.
  s.clip.update(s.field);
  if (!o.clip_specs.empty()) {
    s.clip.check_extent();
    // A clip given here that leaves the camera's target outside (a close-up such as
    // sphere:0.2@0.5,0,0) would show an empty picture: look at the clip's centre instead.
    if (s.clip.is_bounded()) {
      const Box3 b = s.clip.bounds();
      if (!b.contains(s.camera.target)) s.camera.target = b.center();
    }
  }
  s.fit_ranges();  // a typed equation comes without ranges
}

}  // namespace

Scene resolve_scene(const std::string& spec, const SurfaceOverrides& overrides) {
  Scene scene;
  if (const CatalogEntry* e = find_catalog_entry(spec)) {
    scene.surface = make_surface(*e);
  } else if ((file_extension(spec) == "json" || file_extension(spec) == "jsurf") &&
             spec.find('\n') == std::string::npos) {
    scene = read_scene(spec);
  } else {
    if (is_bare_name(spec)) {
      // A lone word is meant as a catalog name; as an equation it would be a constant.
      throw BadInput(fmt::format("'{}' is not a catalog surface{}; `zeroset list` shows them all",
                                 spec, suggestion(spec)));
    }
    ParseResult r = parse_field(spec);
    if (!r.ok()) throw BadInput("cannot read the equation:\n" + r.format());
    scene.surface.field = *r.field;
    scene.surface.ranges.clear();
    apply_overrides(scene, overrides);
    try {
      scene.surface.field.require_parameters();
    } catch (const InvalidArgument& e) {
      if (!is_hyphenated_name(spec)) throw;
      throw InvalidArgument(
          fmt::format("{} ('{}' is read as an equation: it is not a catalog "
                      "surface{}; `zeroset list` shows them all)",
                      e.what(), spec, suggestion(spec)));
    }
    if (scene.surface.clip.is_empty_spec()) scene.surface.clip = default_clip(scene.surface.field);
    return scene;
  }
  apply_overrides(scene, overrides);
  scene.surface.field.require_parameters();
  return scene;
}

namespace {
// Text from a .jsurf file or the command line may hold bytes that are not UTF-8 (in a comment
// of the equation); a JSON document cannot, so they become U+FFFD instead of failing the save.
std::string valid_utf8(const std::string& s) {
  return json::parse(json(s).dump(-1, ' ', false, json::error_handler_t::replace))
      .get<std::string>();
}
}  // namespace

json scene_to_json(const Scene& scene) {
  const Surface& s = scene.surface;
  json j = scene.settings.is_object() ? scene.settings : json::object();
  j["zeroset_scene"] = 1;
  if (!s.name.empty()) j["name"] = valid_utf8(s.name);
  j["equation"] = valid_utf8(s.field.source());
  json params = json::object();
  for (const auto& r : s.ranges) {
    json p = {{"min", r.min}, {"max", r.max}};
    const int idx = s.field.parameter_index(r.name);
    const double v = idx >= 0 ? s.field.parameter_values()[idx] : std::nan("");
    if (std::isfinite(v)) p["value"] = v;
    params[r.name] = p;
  }
  j["parameters"] = params;
  j["clip"] = s.clip.to_specs();
  const Camera& c = s.camera;
  j["camera"] = {{"azimuth_deg", c.azimuth_deg},
                 {"elevation_deg", c.elevation_deg},
                 {"distance", c.distance},
                 {"fov_deg", c.fov_deg},
                 {"target", {c.target.x(), c.target.y(), c.target.z()}}};
  if (c.roll_deg != 0) j["camera"]["roll_deg"] = c.roll_deg;  // older files have none
  if (c.is_orthographic()) {
    j["camera"]["projection"] = projection_name(c.projection);
    j["camera"]["ortho_height"] = c.ortho_height;
  }
  return j;
}

Scene scene_from_json(json j, const std::string& origin) {
  if (!j.is_object()) fail(origin, "/", "a scene file is a JSON object");
  if (j.contains("zeroset_scene")) {
    const json& v = j["zeroset_scene"];
    if (!(v.is_number_integer() && v.get<long long>() == kSceneVersion))
      fail(origin, "/zeroset_scene",
           fmt::format("unknown scene format version {} (this zeroset reads version {})",
                       v.dump().substr(0, 40), kSceneVersion));
  }
  Scene scene;
  Surface& s = scene.surface;
  const CatalogEntry* entry = nullptr;
  if (j.contains("name")) {
    entry = find_catalog_entry(json_read::string(j["name"], origin, "/name"));
  }
  if (j.contains("equation")) {
    const std::string eq = json_read::string(j["equation"], origin, "/equation");
    if (entry && eq == entry->equation) {
      s = make_surface(*entry);
    } else {
      ParseResult r = parse_field(eq);
      if (!r.ok()) fail(origin, "/equation", "cannot read the equation:\n" + r.format());
      s.field = *r.field;
      if (j.contains("name") && j["name"].is_string()) s.name = j["name"].get<std::string>();
    }
  } else if (entry) {
    s = make_surface(*entry);
  } else {
    fail(origin, "/", "needs \"equation\" (or the \"name\" of a catalog surface)");
  }
  if (j.contains("parameters")) {
    const json& ps = j["parameters"];
    if (!ps.is_object()) fail(origin, "/parameters", "expected an object");
    std::vector<ParamSpec> given;
    for (const auto& [name, p] : ps.items()) {
      const std::string where = "/parameters/" + json_read::pointer_token(name);
      if (s.field.parameter_index(name) < 0)
        fail(origin, where, "the equation has no parameter '" + name + "'");
      ParamSpec spec{name, 0, 1};
      double value = std::nan("");
      if (p.is_number()) {
        value = number(p, origin, where);
        spec.max = spec.min;  // no range given: fit_ranges makes one around the value
      } else if (p.is_object()) {
        known_keys(p, {"value", "min", "max"}, origin, where);
        if (p.contains("value")) value = number(p["value"], origin, where + "/value");
        if (p.contains("min")) spec.min = number(p["min"], origin, where + "/min");
        if (p.contains("max")) spec.max = number(p["max"], origin, where + "/max");
        if (!(spec.min < spec.max)) fail(origin, where, "needs min < max");
      } else {
        fail(origin, where, "expected a number or {\"value\", \"min\", \"max\"}");
      }
      // Values and range ends within the one parameter limit, reported at their pointer.
      const std::string& parameter = name;  // a structured binding cannot be captured (clang)
      const auto check = [&](double v, const std::string& at) {
        try {
          check_parameter_value(parameter, v);
        } catch (const InvalidArgument& e) {
          fail(origin, at, e.what());
        }
      };
      if (p.is_object()) {
        if (p.contains("min")) check(spec.min, where + "/min");
        if (p.contains("max")) check(spec.max, where + "/max");
      }
      if (std::isfinite(value)) {
        check(value, p.is_object() ? where + "/value" : where);
        s.field.set_parameter(name, value);
      }
      given.push_back(spec);
    }
    // The file's ranges replace the catalog's of the same names (by a set: a file may give
    // thousands of parameters).
    std::set<std::string_view> names;
    for (const ParamSpec& r : given) names.insert(r.name);
    std::erase_if(s.ranges, [&](const ParamSpec& r) { return names.count(r.name) != 0; });
    s.ranges.insert(s.ranges.end(), given.begin(), given.end());
  }
  if (j.contains("clip")) {
    const json& cj = j["clip"];
    if (!cj.is_array()) fail(origin, "/clip", "expected a list of clip specs like \"sphere:3\"");
    Clip c;
    for (size_t i = 0; i < cj.size(); ++i) {
      if (!cj[i].is_string()) fail(origin, fmt::format("/clip/{}", i), "expected a string");
      try {
        c.add(cj[i].get<std::string>());
      } catch (const BadInput& e) {
        fail(origin, fmt::format("/clip/{}", i), e.what());
      }
    }
    try {
      // A parametric clip is sized by the file's parameter values; one whose parameters get
      // their values later (--param) is sized then (resolve_scene).
      if (!c.is_parametric())
        c.check_extent();
      else if (s.field.missing_parameters().empty())
        c.update(s.field);
    } catch (const BadInput& e) {
      fail(origin, "/clip", e.what());
    }
    s.clip = c;
  }
  if (j.contains("camera")) {
    const json& c = j["camera"];
    if (!c.is_object()) fail(origin, "/camera", "expected an object");
    known_keys(c,
               {"azimuth_deg", "elevation_deg", "distance", "fov_deg", "target", "roll_deg",
                "projection", "ortho_height"},
               origin, "/camera");
    auto num = [&](const char* key, double& out) {
      if (c.contains(key)) out = number(c[key], origin, std::string("/camera/") + key);
    };
    num("azimuth_deg", s.camera.azimuth_deg);
    num("elevation_deg", s.camera.elevation_deg);
    num("distance", s.camera.distance);
    num("fov_deg", s.camera.fov_deg);
    num("roll_deg", s.camera.roll_deg);
    num("ortho_height", s.camera.ortho_height);
    if (c.contains("projection")) {
      const std::optional<Projection> p =
          find_projection(json_read::string(c["projection"], origin, "/camera/projection"));
      if (!p) fail(origin, "/camera/projection", "expected \"perspective\" or \"orthographic\"");
      s.camera.projection = *p;
    }
    if (c.contains("target")) s.camera.target = vec3(c["target"], origin, "/camera/target");
    try {
      validate_camera(s.camera);
    } catch (const SettingError& e) {
      fail(origin, "/camera/" + e.key(), e.why());
    }
  }
  s.fit_ranges();
  // Moved, not copied: a scene's other entries can be large.
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& key = it.key();
    if (key != "zeroset_scene" && key != "name" && key != "equation" && key != "parameters" &&
        key != "clip" && key != "camera")
      scene.settings[key] = std::move(it.value());
  }
  return scene;
}

Scene read_scene(const std::string& path) {
  if (file_extension(path) == "jsurf") return read_jsurf(path);
  return scene_from_json(json_read::parse(json_read::read_file(path), path), path);
}

void write_scene(const Scene& scene, const std::string& path) {
  const std::string text = scene_to_json(scene).dump(2) + "\n";
  // A file zeroset could not read back is not written.
  if (text.size() > json_read::kMaxBytes)
    throw BadInput(fmt::format(
        "{}: the scene would take {:.1f} MiB, more than a scene file may be ({} MiB); fewer "
        "keyframes or clip parts would fit",
        path, static_cast<double>(text.size()) / (1 << 20), json_read::kMaxBytes >> 20));
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace zeroset
