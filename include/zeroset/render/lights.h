#pragma once
/// Parallel lights: the default rig and each light's direction in the world or in the camera's
/// frame. One definition for the CPU renderer and the viewer's GL shading, so that both light
/// a surface the same way.
#include <span>
#include <vector>

#include "zeroset/render/view.h"
#include "zeroset/types.h"

namespace zeroset {

/// A directional light; `direction` points from the surface towards the light. With
/// `follows_camera` the direction is given in camera coordinates (x right, y up, z towards
/// the viewer), otherwise in world coordinates.
struct Light {
  Vec3 direction = Vec3(0.3, 0.5, 1.0);
  Color color = Color(1, 1, 1);
  bool follows_camera = true;
};

/// A light placed in one frame: the unit direction towards it there, and its colour.
struct PlacedLight {
  Vec3 direction;
  Color color;
};

/// The three-light rig used when RenderOptions::lights is empty: a warm key light from the
/// upper left, a cool fill from the right and a rim light from behind, all following the
/// camera.
std::vector<Light> default_lights();

/// The lights that shine (a finite, nonzero direction), in order, with their directions in
/// world coordinates for `view`.
std::vector<PlacedLight> world_lights(std::span<const Light> lights, const View& view);

/// The lights that shine, in order, with their directions in camera coordinates (x right, y up,
/// z towards the viewer: OpenGL's eye space). `world_to_camera` turns world directions into
/// camera ones (its rows: the view's right, up and −forward).
std::vector<PlacedLight> camera_lights(std::span<const Light> lights, const Mat3& world_to_camera);

}  // namespace zeroset
