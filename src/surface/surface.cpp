#include "zeroset/surface/surface.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "zeroset/error.h"

namespace zeroset {

Vec3 Camera::eye(double scene_radius) const {
  const double az = azimuth_deg * M_PI / 180, el = elevation_deg * M_PI / 180;
  const Vec3 dir(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  double dist = distance;
  if (dist <= 0) {
    // Fit a ball of the scene radius into the vertical field of view, with a small margin.
    const double half = 0.5 * fov_deg * M_PI / 180;
    dist = 1.08 * scene_radius / std::sin(half);
  }
  if (is_orthographic()) dist = std::max(dist, 2.5 * scene_radius);
  return target + dist * dir;
}

double Camera::view_height(double scene_radius) const {
  return ortho_height > 0 ? ortho_height : 2.16 * scene_radius;
}

Camera Camera::aimed_at(std::span<const Vec3> points, double min_radius) const {
  if (points.empty() || (is_orthographic() ? ortho_height > 0 : distance > 0)) return *this;
  Vec3 lo = points[0], hi = points[0];
  for (const Vec3& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Vec3 centre = 0.5 * (lo + hi);
  double radius = min_radius;
  for (const Vec3& p : points) radius = std::max(radius, (p - centre).norm());
  Camera c = *this;
  c.target = centre;
  if (is_orthographic()) {
    c.ortho_height = 2.16 * radius;
    return c;
  }
  c.distance = 1.08 * radius / std::sin(0.5 * fov_deg * M_PI / 180);
  return c;
}

CameraFrame Camera::frame(double scene_radius) const {
  CameraFrame f;
  f.eye = eye(scene_radius);
  f.forward = (target - f.eye).normalized();
  // z is up; looking straight up or down, the image's up is the azimuth's direction instead.
  Vec3 r = f.forward.cross(Vec3::UnitZ());
  if (r.norm() < 1e-9) {
    const double az = azimuth_deg * M_PI / 180.0;
    r = f.forward.cross(Vec3(-std::cos(az), -std::sin(az), 0));
  }
  f.right = r.normalized();
  f.up = f.right.cross(f.forward).normalized();
  if (roll_deg != 0) {  // exactly the unrolled frame when there is no roll
    const double a = roll_deg * M_PI / 180.0, c = std::cos(a), s = std::sin(a);
    const Vec3 right = c * f.right + s * f.up;
    f.up = -s * f.right + c * f.up;
    f.right = right;
  }
  return f;
}

std::vector<Vec3> Surface::singular_points() const {
  if (!singular_points_fn) return {};
  std::vector<Vec3> out;
  for (const Vec3& p : singular_points_fn(field))
    if (clip.is_empty_spec() || clip.contains(p, 1e-9)) out.push_back(p);
  return out;
}

Box3 Surface::bounds() const {
  if (!clip.is_bounded())
    throw BadInput("surface '" + label() +
                   "' has no bounded clip volume; add one, e.g. --clip sphere:2 or --clip box:2");
  return clip.bounds();
}

double Surface::scene_radius() const {
  const Box3 b = bounds();
  double r = 0.5 * b.diagonal();
  for (const auto& s : clip.spheres) r = std::min(r, (s.center - b.center()).norm() + s.radius);
  return r;
}

void Surface::fit_ranges() {
  // The given ranges by name (the last of a name wins, as before), so that many parameters
  // cost n log n, not n². Ends beyond kMaxParameterMagnitude are not kept: between them a
  // slider's span max - min would not be finite.
  std::map<std::string_view, const ParamSpec*> given;
  for (const auto& r : ranges)
    if (r.min < r.max && std::abs(r.min) <= kMaxParameterMagnitude &&
        std::abs(r.max) <= kMaxParameterMagnitude)
      given[r.name] = &r;
  std::vector<ParamSpec> out;
  const auto& names = field.parameter_names();
  const auto& values = field.parameter_values();
  for (size_t i = 0; i < names.size(); ++i) {
    const double value = std::isfinite(values[i]) ? values[i] : 0.0;
    const double span = std::max(1.0, std::abs(value));
    ParamSpec spec{names[i], value - span, value + span};
    if (const auto it = given.find(names[i]); it != given.end()) spec = *it->second;
    out.push_back(spec);
  }
  ranges = std::move(out);
}

std::string Surface::label() const { return name.empty() ? field.source() : name; }

}  // namespace zeroset
