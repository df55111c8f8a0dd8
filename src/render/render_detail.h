#pragma once
// Shading and the tile scheduler shared by the surface, point and mesh renderers and the
// POV-Ray export. Private to the render module.
#include <functional>
#include <stop_token>
#include <vector>

#include "zeroset/render/render.h"
#include "zeroset/render/view.h"

namespace zeroset::detail {

/// The three-light rig used when RenderOptions::lights is empty: a warm key light from the
/// upper left, a cool fill from the right and a rim light from behind, all following the camera.
std::vector<Light> default_lights();

/// Phong shading with world-space lights and front/back materials.
struct Shader {
  struct WorldLight {
    Vec3 direction;  // unit, towards the light
    Color color;
  };
  std::vector<WorldLight> lights;
  Material front;
  Material back;

  Shader(const RenderOptions& options, const View& view);
  /// Colour of a point with unit normal `n` (facing the viewer) seen along unit ray `dir`.
  Color shade(const Vec3& n, const Vec3& dir, bool is_front) const;

 private:
  /// A material under the lights: its ambient colour and, per light, the colours its
  /// diffuse and specular terms scale.
  struct Lit {
    Color ambient;
    std::vector<Color> diffuse, specular;
    double shininess = 0;
    int exponent = -1;  // shininess when it is a whole number up to 1024 (else -1)
  };
  Lit lit_front_, lit_back_;
  Lit light_up(const Material& m) const;
};

/// The camera of a render: the option's, else the surface's.
const Camera& camera_of(const Surface& surface, const RenderOptions& options);

/// Checks size and samples; throws InvalidArgument naming the bad value.
void validate(const RenderOptions& options);

/// Worker threads for `requested` (0: all cores).
int thread_count(int requested);

/// Runs `body(x0, y0, x1, y1, worker)` over tile_width × tile_height tiles of the image on
/// `threads` workers (tiles are taken in order from a shared counter). Reports progress from
/// one thread at a time. Returns false when stopped. Exceptions from `body` are rethrown
/// after all workers end.
bool for_each_tile(int width, int height, int tile_width, int tile_height, int threads,
                   std::stop_token stop, const std::function<void(double)>& progress,
                   const std::function<void(int, int, int, int, int)>& body);

/// Stores a linear colour at (x, y) exactly as Image::set_linear does (clamped, gamma 2.2,
/// rounded), through a table of the 255 thresholds between output levels instead of pow.
void store_linear(Image& image, int x, int y, const Color& c);

/// Offsets (in pixels, within [0, 1)) of the samples × samples stratified samples of a pixel.
std::vector<Vec2> sample_offsets(int samples);

}  // namespace zeroset::detail
