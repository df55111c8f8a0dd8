#include "camera_control.h"

#include <algorithm>
#include <cmath>

namespace zeroset::viewer {

void orbit(Camera& camera, double dx_px, double dy_px) {
  camera.azimuth_deg = std::remainder(camera.azimuth_deg - kOrbitDegPerPixel * dx_px, 360.0);
  camera.elevation_deg = std::clamp(camera.elevation_deg + kOrbitDegPerPixel * dy_px,
                                    -kMaxElevationDeg, kMaxElevationDeg);
}

void pan(Camera& camera, const View& view, double dx_px, double dy_px) {
  // One pixel at the target's depth spans pixel_size(depth) world units.
  const double depth = (view.target - view.eye).norm();
  const double unit = view.pixel_size(depth);
  camera.target += unit * (-dx_px * view.right + dy_px * view.up);
}

void zoom(Camera& camera, double factor, double scene_radius) {
  if (camera.is_orthographic()) {  // parallel rays: zooming is the window's height
    camera.ortho_height = std::clamp(camera.view_height(scene_radius) * factor, 0.02 * scene_radius,
                                     100 * scene_radius);
    return;
  }
  Camera c = with_explicit_distance(camera, scene_radius);
  c.distance = std::clamp(c.distance * factor, 0.05 * scene_radius, 50 * scene_radius);
  camera = c;
}

Camera with_explicit_distance(const Camera& camera, double scene_radius) {
  Camera c = camera;
  if (!(c.distance > 0)) c.distance = (c.eye(scene_radius) - c.target).norm();
  return c;
}

Eigen::Matrix4f view_matrix(const View& view) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<1, 3>(0, 0) = view.right.transpose();
  m.block<1, 3>(1, 0) = view.up.transpose();
  m.block<1, 3>(2, 0) = -view.forward.transpose();
  m.block<3, 1>(0, 3) = -(m.block<3, 3>(0, 0) * view.eye);
  return m.cast<float>();
}

Eigen::Matrix4f projection_matrix(const View& view, double near, double far) {
  if (view.orthographic) {
    Eigen::Matrix4d p = Eigen::Matrix4d::Identity();
    p(0, 0) = 1.0 / (view.half_height * view.aspect());
    p(1, 1) = 1.0 / view.half_height;
    p(2, 2) = 2.0 / (near - far);
    p(2, 3) = (far + near) / (near - far);
    return p.cast<float>();
  }
  const double f = 1.0 / view.tan_half_fov;
  Eigen::Matrix4d p = Eigen::Matrix4d::Zero();
  p(0, 0) = f / view.aspect();
  p(1, 1) = f;
  p(2, 2) = (far + near) / (near - far);
  p(2, 3) = 2 * far * near / (near - far);
  p(3, 2) = -1;
  return p.cast<float>();
}

void depth_range(const View& view, const Vec3& center, double radius, double& near, double& far) {
  const double depth = (center - view.eye).dot(view.forward);
  far = std::max(depth + radius, 1e-6);
  // A near plane too close to the eye wastes depth precision; the 1e-3 ratio keeps 24 bits
  // of depth useful when the eye sits inside the scene.
  near = std::max(depth - radius, 1e-3 * far);
  if (view.orthographic) near = std::max(depth - radius, 0.0);  // no precision lost near 0
}

}  // namespace zeroset::viewer
