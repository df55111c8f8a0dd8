// The viewer's camera actions: the viewport, setting, orbiting, panning and zooming.
#include <algorithm>
#include <cmath>

#include "camera_control.h"
#include "viewer_state.h"

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

View ViewerState::view() const {
  return View::from_camera(surface_.camera, surface_.scene_radius(), viewport_w_, viewport_h_);
}

}  // namespace zeroset::viewer
