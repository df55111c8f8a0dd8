// Ray traces an equation exactly and writes the picture as PNG.
//   render_png [OUT.png] [SIZE]      e.g. render_png cayley.png 400
#include <cstdio>
#include <exception>
#include <string>

#include "zeroset/io/image.h"
#include "zeroset/render/render.h"
#include "zeroset/surface/scene.h"

int main(int argc, char** argv) {
  const std::string out = argc > 1 ? argv[1] : "surface.png";
  const int size = argc > 2 ? std::stoi(argv[2]) : 400;
  try {
    // Cayley's cubic with its four nodes, clipped to a ball of radius 2. Free names (here a)
    // are parameters and need values.
    const zeroset::Surface surface = zeroset::resolve_surface(
        "4*a*(x^2 + y^2 + z^2) + 16*x*y*z = a", {.params = {{"a", 1}}, .clip_specs = {"sphere:2"}});

    zeroset::RenderOptions options;
    options.width = options.height = size;
    options.samples = 2;  // 2×2 rays per pixel
    options.camera = surface.camera;
    options.camera->azimuth_deg = 35;

    zeroset::RenderStats stats;
    const zeroset::Image image = zeroset::render_surface(surface, options, &stats);
    zeroset::write_png(image, out);
    std::printf("%s: %lld rays, %lld hits, %s, %.3f s\n", out.c_str(), stats.rays, stats.hits,
                stats.exact ? "exact" : "interval arithmetic", stats.seconds);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "render_png: %s\n", e.what());
    return 1;
  }
  return 0;
}
