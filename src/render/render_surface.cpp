#include <algorithm>
#include <chrono>
#include <vector>

#include "render_detail.h"
#include "zeroset/render/raycast.h"
#include "zeroset/render/render.h"

namespace zeroset {

Image render_surface(const Surface& surface, const RenderOptions& options, RenderStats* stats,
                     std::stop_token stop) {
  const auto start = std::chrono::steady_clock::now();
  detail::validate(options);
  const View view = View::from_camera(detail::camera_of(surface, options),
                                      surface.scene_radius(), options.width, options.height);
  const detail::Shader shader(options, view);
  const int threads = detail::thread_count(options.threads);

  // One caster per worker, built here so that bad input (no clip, missing parameters) is
  // reported before any thread starts.
  std::vector<SurfaceRayCaster> casters;
  for (int w = 0; w < threads; ++w) casters.emplace_back(surface, view.eye);
  struct Counters {
    long long rays = 0, hits = 0, singular = 0;
    char pad[64 - 3 * sizeof(long long)];  // one cache line per worker
  };
  std::vector<Counters> counters(static_cast<size_t>(threads));

  const std::vector<Vec2> offsets = detail::sample_offsets(options.samples);
  const double weight = 1.0 / static_cast<double>(offsets.size());
  Image image(options.width, options.height);
  Image background(1, 1);  // the background's bytes, copied into pixels no ray hits
  detail::store_linear(background, 0, 0, options.background);
  const bool finished = detail::for_each_tile(
      options.width, options.height, threads, stop, options.progress,
      [&](int x0, int y0, int x1, int y1, int worker) {
        SurfaceRayCaster& caster = casters[static_cast<size_t>(worker)];
        Counters& count = counters[static_cast<size_t>(worker)];
        SurfaceHit hit;
        for (int y = y0; y < y1; ++y)
          for (int x = x0; x < x1; ++x) {
            Color sum = Color::Zero();
            bool any = false;
            for (const Vec2& o : offsets) {
              const Vec3 dir = view.direction(x + o.x(), y + o.y());
              ++count.rays;
              if (caster.intersect(dir, hit)) {
                ++count.hits;
                count.singular += hit.singular;
                sum += shader.shade(hit.normal, dir, hit.front);
                any = true;
              } else {
                sum += options.background;
              }
            }
            if (any)
              detail::store_linear(image, x, y, sum * weight);
            else
              std::copy_n(background.rgb.data(), 3, image.pixel(x, y));
          }
      });
  if (!finished) return {};
  if (stats) {
    *stats = {};
    for (const Counters& c : counters) {
      stats->rays += c.rays;
      stats->hits += c.hits;
      stats->singular_normals += c.singular;
    }
    stats->threads = threads;
    stats->exact = casters.front().is_exact();
    stats->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return image;
}

}  // namespace zeroset
