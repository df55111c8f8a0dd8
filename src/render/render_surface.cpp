#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "render_detail.h"
#include "zeroset/render/raycast.h"
#include "zeroset/render/render.h"

namespace zeroset {
namespace {

constexpr double kNoHit = std::numeric_limits<double>::quiet_NaN();
// Tiles are bands of whole rows: each row of rays is expanded once (SurfaceRayCaster::
// begin_row), and 200 bands of an 800-row picture keep two or more workers evenly busy.
constexpr int kBandRows = 4;

/// Where a ray's first hit is expected from its neighbours' hits (pixel coherence): the left
/// neighbour continued by the step from the upper left to the upper neighbour (a plane
/// through the three), or linearly along the row, or the nearest neighbour itself. The
/// spread leaves room for twice the change seen; a guess that is off only costs time.
RootGuess guess_from_neighbours(double left, double left2, double up, double up_left) {
  RootGuess g;
  constexpr double kFloor = 1e-4;  // relative to t: room for the curvature of the surface
  if (!std::isnan(left) && !std::isnan(up) && !std::isnan(up_left)) {
    g.t = left + up - up_left;
    g.spread = 2 * (std::abs(left - up_left) + std::abs(up - up_left)) + kFloor * g.t;
  } else if (!std::isnan(left) && !std::isnan(left2)) {
    g.t = 2 * left - left2;
    g.spread = 2 * std::abs(left - left2) + kFloor * g.t;
  } else if (!std::isnan(left) || !std::isnan(up)) {
    g.t = !std::isnan(left) ? left : up;
    g.spread = 10 * kFloor * g.t;
  }
  return g;
}

}  // namespace

Image render_surface(const Surface& surface, const RenderOptions& options, RenderStats* stats,
                     std::stop_token stop) {
  const auto start = std::chrono::steady_clock::now();
  detail::validate(options);
  const View view = View::from_camera(detail::camera_of(surface, options),
                                      surface.scene_radius(), options.width, options.height);
  const detail::Shader shader(options, view);
  const int threads = detail::thread_count(options.threads);

  // One caster per worker, built here so that bad input (no clip, missing parameters) is
  // reported before any thread starts. A picture needs the hit far below a pixel, not to
  // 1e-12 of the clipped segment: 1e-9 (about 1e-8 of the scene's size, where a pixel is
  // about 1e-3) saves a Newton step on most rays.
  RaycastOptions cast_options;
  cast_options.roots.refine_tolerance = 1e-9;
  std::vector<SurfaceRayCaster> casters;
  for (int w = 0; w < threads; ++w) casters.emplace_back(surface, view.eye, cast_options);
  struct Worker {
    long long rays = 0, hits = 0, singular = 0;
    // Hit parameters of the band's previous and current row of rays (NaN: no hit), and per
    // pixel of the band the sum of the colours of the samples that hit and their number.
    std::vector<double> above, current;
    std::vector<Color> sums;
    std::vector<int> hit_samples;
    char pad[64];  // keeps the counters of different workers on different cache lines
  };
  std::vector<Worker> workers(static_cast<size_t>(threads));

  const int samples = options.samples;
  const double weight = 1.0 / (samples * samples);
  std::vector<double> offsets;  // of the samples within a pixel, along x and along y
  for (int i = 0; i < samples; ++i) offsets.push_back((i + 0.5) / samples);
  Image image(options.width, options.height);
  const detail::GammaTable& gamma = detail::gamma_table();
  std::uint8_t background[3];  // the background's bytes, copied into pixels no ray hits
  gamma.store(background, options.background);
  const bool finished = detail::for_each_tile(
      options.width, options.height, options.width, kBandRows, threads, stop, options.progress,
      [&](int x0, int y0, int x1, int y1, int worker) {
        SurfaceRayCaster& caster = casters[static_cast<size_t>(worker)];
        Worker& w = workers[static_cast<size_t>(worker)];
        // The band's rays form a grid of samples × samples per pixel, cast row by row.
        const int width = x1 - x0, columns = width * samples, rows = (y1 - y0) * samples;
        w.above.assign(static_cast<size_t>(columns), kNoHit);
        w.current.assign(static_cast<size_t>(columns), kNoHit);
        w.sums.resize(static_cast<size_t>(width * (y1 - y0)));  // set by a pixel's first hit
        w.hit_samples.assign(w.sums.size(), 0);
        SurfaceHit hit;
        Vec3 base, step;
        for (int r = 0; r < rows; ++r) {
          const int row_of_pixels = r / samples;
          view.row(y0 + row_of_pixels + offsets[static_cast<size_t>(r % samples)], base, step);
          caster.begin_row(base, step);
          double s_min, s_max;  // rays outside miss the clip volume
          caster.row_extent(s_min, s_max);
          double* t = w.current.data();
          const double* up = w.above.data();
          Color* sums = &w.sums[static_cast<size_t>(row_of_pixels * width)];
          int* hit_samples = &w.hit_samples[static_cast<size_t>(row_of_pixels * width)];
          for (int x = x0, c = 0; x < x1; ++x)
            for (int i = 0; i < samples; ++i, ++c) {
              const double s = x + offsets[static_cast<size_t>(i)];
              t[c] = kNoHit;
              if (s < s_min || s > s_max) continue;
              const RootGuess guess =
                  guess_from_neighbours(c > 0 ? t[c - 1] : kNoHit, c > 1 ? t[c - 2] : kNoHit,
                                        up[c], c > 0 ? up[c - 1] : kNoHit);
              if (!caster.intersect_in_row(s, hit, guess)) continue;
              t[c] = hit.t;
              ++w.hits;
              w.singular += hit.singular;
              const Color color =
                  shader.shade(hit.normal, (base + s * step).normalized(), hit.front);
              sums[x - x0] = hit_samples[x - x0]++ == 0 ? color : Color(sums[x - x0] + color);
            }
          w.rays += columns;
          std::swap(w.above, w.current);
        }
        for (int y = y0; y < y1; ++y) {
          std::uint8_t* out = image.pixel(x0, y);
          for (int x = x0; x < x1; ++x, out += 3) {
            const size_t pixel = static_cast<size_t>((y - y0) * width + (x - x0));
            if (const int n = w.hit_samples[pixel]; n > 0) {
              gamma.store(out, (w.sums[pixel] + (samples * samples - n) * options.background) *
                                   weight);
            } else {
              // Byte by byte: a 3-byte copy compiles to a call of memcpy.
              out[0] = background[0];
              out[1] = background[1];
              out[2] = background[2];
            }
          }
        }
      });
  if (!finished) return {};
  if (stats) {
    *stats = {};
    for (const Worker& w : workers) {
      stats->rays += w.rays;
      stats->hits += w.hits;
      stats->singular_normals += w.singular;
    }
    stats->threads = threads;
    stats->exact = casters.front().is_exact();
    stats->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return image;
}

}  // namespace zeroset
