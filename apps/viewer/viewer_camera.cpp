// The viewer's camera actions: the viewport, setting, orbiting, panning and zooming.
#include <algorithm>
#include <cmath>

#include "camera_control.h"
#include "viewer_state.h"
#include "zeroset/surface/settings.h"

namespace zeroset::viewer {

// ---- camera ------------------------------------------------------------------------------------

void ViewerState::set_viewport(int width, int height) {
  width = std::max(width, 1);
  height = std::max(height, 1);
  if (width == viewport_w_ && height == viewport_h_) return;
  viewport_w_ = width;
  viewport_h_ = height;
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

bool ViewerState::set_camera(const Camera& camera) {
  return guard("camera", [&] {
    Camera c = camera;
    c.elevation_deg = std::clamp(c.elevation_deg, -kMaxElevationDeg, kMaxElevationDeg);
    c = with_explicit_distance(c, surface_.scene_radius());
    View::from_camera(c, surface_.scene_radius(), viewport_w_, viewport_h_);  // validates
    surface_.camera = c;
    if (mode_ == Mode::kRaytrace) needs_restart_ = true;
  });
}

void ViewerState::orbit(double dx_px, double dy_px) {
  viewer::orbit(surface_.camera, dx_px, dy_px);
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

void ViewerState::pan(double dx_px, double dy_px) {
  viewer::pan(surface_.camera, view(), dx_px, dy_px);
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

void ViewerState::zoom(double factor) {
  if (!(factor > 0) || !std::isfinite(factor)) return;
  viewer::zoom(surface_.camera, factor, surface_.scene_radius());
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

void ViewerState::reset_view() {
  surface_.camera = home_camera_;
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

void ViewerState::follow_clip(const Clip& next) {
  if (!next.is_parametric() || !surface_.clip.is_bounded() || !next.is_bounded()) return;
  Surface after;
  after.clip = next;
  const double r0 = surface_.scene_radius(), r1 = after.scene_radius();
  if (!(r0 > 0 && r1 > 0) || r0 == r1) return;
  const Vec3 c0 = surface_.bounds().center(), c1 = after.bounds().center();
  const auto scaled = [&](Camera c) {
    c = with_explicit_distance(c, r0);
    c.distance = std::min(c.distance * r1 / r0, kMaxCameraLength);
    c.target = c1 + (c.target - c0) * (r1 / r0);
    return c;
  };
  surface_.camera = scaled(surface_.camera);
  home_camera_ = scaled(home_camera_);
  if (mode_ == Mode::kRaytrace) needs_restart_ = true;
}

View ViewerState::view() const {
  return View::from_camera(surface_.camera, surface_.scene_radius(), viewport_w_, viewport_h_);
}

}  // namespace zeroset::viewer
