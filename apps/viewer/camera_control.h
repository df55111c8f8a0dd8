#pragma once
// Mouse-driven orbit camera and the OpenGL matrices of a zeroset::View, so the GL modes show
// exactly the picture the ray caster (which uses the same View) shows.
#include <Eigen/Core>

#include "zeroset/render/view.h"
#include "zeroset/surface/surface.h"

namespace zeroset::viewer {

/// Degrees of rotation per pixel of mouse motion.
inline constexpr double kOrbitDegPerPixel = 0.35;
/// Elevation stays inside ±kMaxElevationDeg, so the view never flips over the pole.
inline constexpr double kMaxElevationDeg = 89;

/// Turns the camera around its target: dx pixels to the right turn it left (the surface
/// follows the mouse), dy pixels down tilt it up.
void orbit(Camera& camera, double dx_px, double dy_px);
/// Moves the target in the image plane so that the surface follows the mouse by (dx, dy)
/// pixels of `view` (the view the camera is currently seen through).
void pan(Camera& camera, const View& view, double dx_px, double dy_px);
/// Multiplies the distance by `factor` (< 1 comes closer), kept within [0.05, 50] scene radii.
void zoom(Camera& camera, double factor, double scene_radius);
/// The same camera with an explicit distance (Camera::distance 0 means "fit the scene").
Camera with_explicit_distance(const Camera& camera, double scene_radius);

/// World → eye coordinates (OpenGL convention: looking along −z, y up).
Eigen::Matrix4f view_matrix(const View& view);
/// Eye → clip coordinates for `view`'s field of view and aspect; depth range [near, far].
Eigen::Matrix4f projection_matrix(const View& view, double near, double far);
/// Near and far planes that hold a ball of `radius` around `center` seen from `view`.
void depth_range(const View& view, const Vec3& center, double radius, double& near, double& far);

}  // namespace zeroset::viewer
