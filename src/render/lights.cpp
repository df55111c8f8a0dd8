#include "zeroset/render/lights.h"

namespace zeroset {
namespace {

bool shines(const Light& l) { return l.direction.norm() > 0 && l.direction.allFinite(); }

}  // namespace

std::vector<Light> default_lights() {
  return {
      {.direction = Vec3(-0.45, 0.55, 1.0), .color = Color(0.78, 0.76, 0.72)},
      {.direction = Vec3(0.9, -0.15, 0.5), .color = Color(0.22, 0.24, 0.3)},
      {.direction = Vec3(0.1, 0.9, -0.7), .color = Color(0.25, 0.25, 0.25)},
  };
}

std::vector<PlacedLight> world_lights(std::span<const Light> lights, const View& view) {
  std::vector<PlacedLight> placed;
  for (const Light& l : lights) {
    if (!shines(l)) continue;
    const Vec3 d = l.follows_camera ? view.camera_to_world(l.direction) : l.direction;
    placed.push_back({d.normalized(), l.color});
  }
  return placed;
}

std::vector<PlacedLight> camera_lights(std::span<const Light> lights, const Mat3& world_to_camera) {
  std::vector<PlacedLight> placed;
  for (const Light& l : lights) {
    if (!shines(l)) continue;
    const Vec3 d = l.follows_camera ? l.direction : Vec3(world_to_camera * l.direction);
    placed.push_back({d.normalized(), l.color});
  }
  return placed;
}

}  // namespace zeroset
