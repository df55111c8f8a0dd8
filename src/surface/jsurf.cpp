#include "zeroset/surface/jsurf.h"

#include <fmt/core.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <optional>

#include "jsurf_detail.h"
#include "properties_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/surface/json_read.h"
#include "zeroset/surface/settings.h"

namespace zeroset {
namespace {

using json = nlohmann::json;
using detail::PropertyValue;
using Props = std::map<std::string, PropertyValue>;
using Mat4 = Eigen::Matrix4d;

// jsurf's camera defaults: a file without camera_fov_y is seen with 60 degrees.
constexpr double kJsurfFovDeg = 60;
using detail::kJsurfGamma;
using detail::kJsurfLights;

json linear_json(const Vec3& display) {
  return {std::pow(display.x(), kJsurfGamma), std::pow(display.y(), kJsurfGamma),
          std::pow(display.z(), kJsurfGamma)};
}

class Reader {
 public:
  Reader(const Props& props, const std::string& origin) : props_(props), origin_(origin) {}

  const PropertyValue* find(const std::string& key) const {
    const auto it = props_.find(key);
    return it == props_.end() ? nullptr : &it->second;
  }
  bool has(const std::string& key) const { return find(key) != nullptr; }
  int line(const std::string& key) const { return find(key) ? find(key)->line : 0; }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    const PropertyValue* v = find(key);
    if (v) throw BadInput(fmt::format("{}:{}: {}: {}", origin_, v->line, key, what));
    throw BadInput(fmt::format("{}: {}: {}", origin_, key, what));
  }

  /// Whitespace-separated numbers (Java's Scanner), exactly `n` of them, all finite.
  std::vector<double> numbers(const std::string& key, size_t n) const {
    const std::string& text = find(key)->value;
    std::vector<double> out;
    size_t i = 0;
    while (true) {
      while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
      if (i == text.size()) break;
      size_t j = i;
      while (j < text.size() && !std::isspace(static_cast<unsigned char>(text[j]))) ++j;
      std::string_view word(text.data() + i, j - i);
      const std::string shown(word);
      if (!word.empty() && word.front() == '+') word.remove_prefix(1);
      // Java also reads "1.5f" and "2d".
      if (word.size() > 1 && std::string_view("fFdD").find(word.back()) != std::string_view::npos &&
          (std::isdigit(static_cast<unsigned char>(word[word.size() - 2])) ||
           word[word.size() - 2] == '.'))
        word.remove_suffix(1);
      double v = 0;
      const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
      if (ec != std::errc() || end != word.data() + word.size() || !std::isfinite(v))
        fail(key, fmt::format("'{}' is not a finite number", shown));
      out.push_back(v);
      i = j;
    }
    if (out.size() != n)
      fail(key, n == 1 ? fmt::format("expected a number, found '{}'", text)
                       : fmt::format("expected {} numbers, found {}", n, out.size()));
    return out;
  }
  double number(const std::string& key) const { return numbers(key, 1)[0]; }
  double number_in(const std::string& key, double lo, double hi) const {
    const double v = number(key);
    if (!(v >= lo && v <= hi)) fail(key, fmt::format("{} must lie in [{}, {}]", v, lo, hi));
    return v;
  }
  Vec3 vec3(const std::string& key) const {
    const std::vector<double> v = numbers(key, 3);
    return Vec3(v[0], v[1], v[2]);
  }
  Vec3 color(const std::string& key) const {
    const Vec3 c = vec3(key);
    if ((c.array() < 0).any() || (c.array() > 1).any())
      fail(key, fmt::format("colour components must lie in [0, 1], found {} {} {}", c.x(), c.y(),
                            c.z()));
    return c;
  }
  /// 16 numbers, row by row (jsurf's BasicIO: m00 m01 m02 m03 m10 ...).
  Mat4 matrix(const std::string& key) const {
    const std::vector<double> v = numbers(key, 16);
    Mat4 m;
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) m(r, c) = v[static_cast<size_t>(4 * r + c)];
    return m;
  }
  Mat4 matrix_or_identity(const std::string& key) const {
    return has(key) ? matrix(key) : Mat4(Mat4::Identity());
  }

 private:
  const Props& props_;
  const std::string& origin_;
};

/// An affine map split into a uniform scale, a rotation and a translation.
struct Similarity {
  double scale = 1;
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();
};

// A is scale · rotation plus a translation (after dividing by A(3,3)), up to the rounding of
// matrices typed with a few digits; the rotation is made exactly orthonormal. None for a
// shear, a mirror, a projective or a singular map.
std::optional<Similarity> similarity(Mat4 a) {
  if (!a.allFinite() || a(3, 3) == 0) return std::nullopt;
  a /= a(3, 3);
  const Mat3 l = a.topLeftCorner<3, 3>();
  const double size = l.norm();
  if (!(size > 0) || a.block<1, 3>(3, 0).norm() > 1e-9 * size) return std::nullopt;
  const double det = l.determinant();
  if (!(det > 0)) return std::nullopt;
  Similarity s;
  s.scale = std::cbrt(det);
  const Mat3 q = l / s.scale;
  if ((q.transpose() * q - Mat3::Identity()).norm() > 1e-4) return std::nullopt;
  const Eigen::JacobiSVD<Mat3> svd(q, Eigen::ComputeFullU | Eigen::ComputeFullV);
  s.rotation = svd.matrixU() * svd.matrixV().transpose();
  s.translation = a.topRightCorner<3, 1>();
  return s;
}

double degrees(double radians) { return radians * 180.0 / M_PI; }

json material_json(const Reader& r, const std::string& prefix) {
  json m = json::object();
  if (r.has(prefix + "color")) m["diffuse"] = linear_json(r.color(prefix + "color"));
  if (r.has(prefix + "ambient_intensity"))
    m["ambient"] = r.number_in(prefix + "ambient_intensity", 0, 1);
  if (r.has(prefix + "diffuse_intensity"))  // checked, not used: see docs/scenes.md
    r.number_in(prefix + "diffuse_intensity", 0, 1e9);
  if (r.has(prefix + "specular_intensity"))
    m["specular"] = r.number_in(prefix + "specular_intensity", 0, 1e9);
  if (r.has(prefix + "shininess")) m["shininess"] = r.number_in(prefix + "shininess", 0, 1e9);
  return m;
}

}  // namespace

Scene jsurf_to_scene(std::string_view text, const std::string& origin) {
  const Props props = detail::parse_properties(text, origin);
  const Reader r(props, origin);
  Scene scene;
  Surface& s = scene.surface;

  // The equation and its parameters.
  if (!r.has("surface_equation"))
    throw BadInput(
        fmt::format("{}: no surface_equation entry (a SURFER file gives its surface "
                    "as surface_equation=...)",
                    origin));
  const std::string& equation = r.find("surface_equation")->value;
  if (equation.find_first_not_of(" \t\f") == std::string::npos)
    r.fail("surface_equation", "the equation is empty");
  ParseResult parsed = parse_field(equation);
  if (!parsed.ok()) r.fail("surface_equation", "cannot read the equation:\n" + parsed.format());
  s.field = *parsed.field;
  const std::string prefix = "surface_parameter_";
  for (const auto& [key, value] : props) {
    if (key.rfind(prefix, 0) != 0) continue;
    const double v = r.number(key);
    // SURFER saves all four sliders; those the equation does not use are ignored.
    if (s.field.parameter_index(key.substr(prefix.size())) >= 0) {
      try {
        s.field.set_parameter(key.substr(prefix.size()), v);
      } catch (const InvalidArgument& e) {  // beyond the parameter values' limit
        r.fail(key, e.what());
      }
    }
  }
  if (r.has("surface_name")) s.title = r.find("surface_name")->value;

  // jsurf's transforms (its RayCreator): camera space -> clipping space is T·C⁻¹ with
  // T = transform_matrix·rotation_matrix and C = camera_transform; clipping space -> surface
  // space is S = surface_transform_matrix·diag(10^scale_factor); the clip is the unit ball
  // of clipping space.
  double scale = 1;
  if (r.has("scale_factor")) {
    scale = std::pow(10.0, r.number_in("scale_factor", -100, 100));
  }
  Mat4 S = r.matrix_or_identity("surface_transform_matrix");
  S.topLeftCorner<3, 4>() *= scale;
  const std::optional<Similarity> clip = similarity(S);
  if (!clip)
    r.fail(r.has("surface_transform_matrix") ? "surface_transform_matrix" : "scale_factor",
           "the clip sphere's transform is not a rotation with a uniform scale");
  // Without a surface transform the radius is 10^scale_factor itself, not its cube root's cube.
  const double radius = r.has("surface_transform_matrix") ? clip->scale : scale;
  s.clip = {};
  try {  // through its spec (exact: the shortest round trip), so the clip limits apply
    s.clip.add(Clip::sphere(radius, clip->translation).to_specs().front());
  } catch (const InvalidArgument& e) {
    r.fail(r.has("surface_transform_matrix") ? "surface_transform_matrix" : "scale_factor",
           e.what());
  }

  const bool has_camera = r.has("camera_transform");
  Mat4 C = r.matrix_or_identity("camera_transform");
  if (!(std::abs(C.determinant()) > 1e-300)) r.fail("camera_transform", "the matrix is singular");
  const Mat4 T = r.matrix_or_identity("transform_matrix") * r.matrix_or_identity("rotation_matrix");
  const std::optional<Similarity> view = similarity(S * T * C.inverse());
  const std::string blame = r.has("rotation_matrix")    ? "rotation_matrix"
                            : r.has("camera_transform") ? "camera_transform"
                                                        : "transform_matrix";
  if (!view)
    r.fail(blame,
           "with the other transforms it is not a rotation with a uniform scale and a "
           "translation (zeroset's camera cannot show a sheared or mirrored view)");

  // The camera: its frame in surface space is the rotation's columns (x right, y up, z towards
  // the viewer); it looks at the point of its axis nearest to the clip sphere's centre.
  bool orthographic = false;
  if (r.has("camera_type")) {
    const std::string& type = r.find("camera_type")->value;
    orthographic = type == "ORTHOGRAPHIC_CAMERA";
    if (!orthographic && type != "PERSPECTIVE_CAMERA")
      r.fail("camera_type", fmt::format("'{}' is neither PERSPECTIVE_CAMERA nor "
                                        "ORTHOGRAPHIC_CAMERA",
                                        type));
  }
  Camera& cam = s.camera;
  cam.fov_deg =
      r.has("camera_fov_y") ? r.number_in("camera_fov_y", kMinFovDeg, kMaxFovDeg) : kJsurfFovDeg;
  cam.projection = orthographic ? Projection::orthographic : Projection::perspective;
  cam.ortho_height = 0;  // without camera_height zeroset frames the clip sphere
  if (orthographic && r.has("camera_height")) {
    // In camera space, whose units the view's scale turns into the surface's.
    const double h = r.number("camera_height");
    if (!(h > 0 && h * view->scale <= kMaxCameraLength))
      r.fail("camera_height",
             fmt::format("{} must be positive and at most {:g} in the surface's units", h,
                         kMaxCameraLength));
    cam.ortho_height = h * view->scale;
  }
  const Vec3 right = view->rotation.col(0), back = view->rotation.col(2);
  const Vec3 centre = clip->translation;
  cam.target = centre;
  cam.distance = 0;  // without camera_transform zeroset frames the clip sphere
  if (has_camera) {
    const Vec3 eye = view->translation;
    const double d = (centre - eye).dot(-back);
    // Parallel rays see the same picture from any point of their axis: an orthographic eye
    // at or beyond the centre starts its rays where zeroset chooses (outside the clip).
    if (!(d > 1e-12 * clip->scale) && !orthographic)
      r.fail("camera_transform", "the camera looks away from the clip sphere's centre");
    cam.target = eye - d * back;
    cam.distance = d > 1e-12 * clip->scale ? d : 0;
  }
  cam.elevation_deg = degrees(std::asin(std::clamp(back.z(), -1.0, 1.0)));
  cam.azimuth_deg =
      std::hypot(back.x(), back.y()) > 1e-12 ? degrees(std::atan2(back.y(), back.x())) : 0.0;
  cam.roll_deg = 0;
  const CameraFrame unrolled = cam.frame(clip->scale);
  cam.roll_deg = degrees(std::atan2(right.dot(unrolled.up), right.dot(unrolled.right)));
  try {
    validate_camera(cam);
  } catch (const SettingError& e) {
    r.fail(blame, e.what());
  }

  // Colours and lights, as the scene's "render" object.
  json render = json::object();
  if (r.has("background_color")) render["background"] = linear_json(r.color("background_color"));
  for (const char* side : {"front", "back"}) {
    json m = material_json(r, std::string(side) + "_material_");
    if (!m.empty()) render[side] = m;
  }
  bool any_light = false;
  for (const auto& [key, value] : props) any_light = any_light || key.rfind("light_", 0) == 0;
  if (any_light) {
    // jsurf's lights are points in camera space; zeroset's follow the camera as directions,
    // here from the clip sphere's centre towards each light.
    const Eigen::Vector4d c4 = C * T.inverse() * Eigen::Vector4d(0, 0, 0, 1);
    const Vec3 centre_cam = c4.head<3>() / c4.w();
    json lights = json::array();
    for (int i = 0; i < kJsurfLights; ++i) {
      const std::string status = fmt::format("light_status_{}", i);
      if (!r.has(status)) continue;  // jsurf: a light without a status is off
      const std::string& on = r.find(status)->value;
      if (on != "ON" && on != "OFF") r.fail(status, fmt::format("'{}' is neither ON nor OFF", on));
      const std::string pos_key = fmt::format("light_position_{}", i);
      const std::string color_key = fmt::format("light_color_{}", i);
      const std::string intensity_key = fmt::format("light_intensity_{}", i);
      const Vec3 position = r.has(pos_key) ? r.vec3(pos_key) : Vec3::Zero();
      const Vec3 color = r.has(color_key) ? r.color(color_key) : Vec3(1, 1, 1);
      const double intensity = r.has(intensity_key) ? r.number_in(intensity_key, 0, 1e9) : 1.0;
      if (on != "ON") continue;
      const Vec3 direction = position - centre_cam;
      if (!(direction.norm() > 1e-12 * (1 + centre_cam.norm())))
        r.fail(r.has(pos_key) ? pos_key : status,
               "the light sits at the clip sphere's centre; zeroset's lights shine from a "
               "direction");
      const Vec3 shown = (intensity * color).cwiseMin(Vec3(1, 1, 1));
      lights.push_back({{"direction", {direction.x(), direction.y(), direction.z()}},
                        {"color", linear_json(shown)},
                        {"follows_camera", true}});
    }
    if (lights.empty())  // every light off: only the ambient part remains
      lights.push_back({{"direction", {0, 0, 1}}, {"color", {0, 0, 0}}, {"follows_camera", true}});
    render["lights"] = lights;
  }
  if (!render.empty()) scene.settings["render"] = render;
  s.fit_ranges();
  return scene;
}

Scene read_jsurf(const std::string& path) {
  return jsurf_to_scene(json_read::read_file(path), path);
}

}  // namespace zeroset
