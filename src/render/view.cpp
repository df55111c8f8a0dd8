#include "zeroset/render/view.h"

#include <cmath>
#include <numbers>
#include <string>

#include "zeroset/error.h"

namespace zeroset {

View View::from_camera(const Camera& camera, double scene_radius, int width, int height) {
  if (width <= 0 || height <= 0)
    throw InvalidArgument("image size", std::to_string(width) + "x" + std::to_string(height),
                          "width and height must be positive");
  if (!(camera.fov_deg > 0 && camera.fov_deg < 180))
    throw InvalidArgument("field of view", std::to_string(camera.fov_deg),
                          "must lie strictly between 0 and 180 degrees");
  View v;
  v.width = width;
  v.height = height;
  v.target = camera.target;
  v.eye = camera.eye(scene_radius);
  v.tan_half_fov = std::tan(0.5 * camera.fov_deg * std::numbers::pi / 180.0);
  if (camera.is_orthographic()) {
    const double h = camera.view_height(scene_radius);
    if (!(h > 0 && std::isfinite(h)))
      throw InvalidArgument("orthographic height", std::to_string(h),
                            "must be positive and finite");
    v.orthographic = true;
    v.half_height = 0.5 * h;
  }
  const Vec3 to_target = v.target - v.eye;
  if (!v.eye.allFinite() || !v.target.allFinite() || !(to_target.norm() > 0))
    throw InvalidArgument("camera",
                          "eye " + std::to_string(v.eye.x()) + "," + std::to_string(v.eye.y()) +
                              "," + std::to_string(v.eye.z()),
                          "the eye must be finite and differ from the target");
  const CameraFrame f = camera.frame(scene_radius);
  v.forward = f.forward;
  v.right = f.right;
  v.up = f.up;
  return v;
}

Vec3 View::direction(double x, double y) const {
  if (orthographic) return forward;
  const double sx = (2.0 * x / width - 1.0) * tan_half_fov * aspect();
  const double sy = (1.0 - 2.0 * y / height) * tan_half_fov;
  return (forward + sx * right + sy * up).normalized();
}

Vec3 View::origin(double x, double y) const {
  if (!orthographic) return eye;
  const double sx = (2.0 * x / width - 1.0) * half_height * aspect();
  const double sy = (1.0 - 2.0 * y / height) * half_height;
  return eye + sx * right + sy * up;
}

void View::row_origins(double y, Vec3& base, Vec3& step) const {
  if (!orthographic) {
    base = eye;
    step = Vec3::Zero();
    return;
  }
  const double half_width = half_height * aspect();
  const double sy = (1.0 - 2.0 * y / height) * half_height;
  base = eye - half_width * right + sy * up;
  step = (2.0 * half_width / width) * right;
}

void View::row(double y, Vec3& base, Vec3& step) const {
  if (orthographic) {
    base = forward;
    step = Vec3::Zero();
    return;
  }
  const double half_width = tan_half_fov * aspect();  // of the image plane at depth 1
  const double sy = (1.0 - 2.0 * y / height) * tan_half_fov;
  base = forward - half_width * right + sy * up;
  step = (2.0 * half_width / width) * right;
}

bool View::project(const Vec3& p, double& x, double& y, double& depth) const {
  const Vec3 q = p - eye;
  depth = q.dot(forward);
  if (!(depth > 0)) return false;
  if (orthographic) {
    x = (q.dot(right) / (half_height * aspect()) + 1.0) * 0.5 * width;
    y = (1.0 - q.dot(up) / half_height) * 0.5 * height;
    return true;
  }
  const double sx = q.dot(right) / depth, sy = q.dot(up) / depth;
  x = (sx / (tan_half_fov * aspect()) + 1.0) * 0.5 * width;
  y = (1.0 - sy / tan_half_fov) * 0.5 * height;
  return true;
}

}  // namespace zeroset
