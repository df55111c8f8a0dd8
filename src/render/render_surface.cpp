#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <vector>

#include "overlay_detail.h"
#include "render_detail.h"
#include "zeroset/error.h"
#include "zeroset/render/raycast.h"
#include "zeroset/render/render.h"
#include "zeroset/surface/field_survey.h"

namespace zeroset {

RootGuess detail::guess_from_neighbours(double left, double left2, double up, double up_left) {
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

namespace {

using detail::guess_from_neighbours;

constexpr double kNoHit = std::numeric_limits<double>::quiet_NaN();
// Tiles are bands of whole rows: each row of rays is expanded once (SurfaceRayCaster::
// begin_row), and 200 bands of an 800-row picture keep two or more workers evenly busy.
constexpr int kBandRows = 4;

/// Hits of a row waiting to be shaded four at a time (Shader::shade_rays4): normals and ray
/// directions component by component, sides, and the pixel (in the band's row) of each.
struct ShadeQueue {
  double n[3][4], ray[3][4];
  bool front[4];
  int pixel[4];
  int size = 0;
};

/// Draws the singular overlay into a band of pixels [x0, x1) × [y0, y1) whose rays are cast:
/// `depth` holds the hit parameter of every ray (NaN: a miss) row by row, the ray in column
/// c of row r being base[r] + ray_s[c]·step[r]; per pixel, `sums` and `hit_samples` hold the
/// sum of the colours of the samples that hit the surface and their number. A sample the
/// overlay meets nearer takes the overlay's colour in place of its own: a hit's own colour is
/// not kept per sample, so the pixel's mean surface colour stands for it (exact without
/// anti-aliasing, and wherever a pixel's hits have one colour). `sums` and `hit_samples` then
/// hold the pixel's colour and samples × samples, or are left alone where nothing changed.
void composite_overlay(const detail::OverlayScene& overlay, int x0, int y0, int x1, int y1,
                       int samples, const std::vector<double>& ray_s, const Color& background,
                       const std::vector<double>& depth, const std::vector<Vec3>& base,
                       const std::vector<Vec3>& step, std::vector<detail::OverlayHit>& on_top,
                       std::vector<std::uint8_t>& touched, std::vector<Color>& sums,
                       std::vector<int>& hit_samples) {
  const int width = x1 - x0, ns = samples * samples;
  const size_t columns = static_cast<size_t>(width * samples);
  // Sample s = j·samples + i of pixel (x, y) is the ray in row (y − y0)·samples + j, column
  // (x − x0)·samples + i (the order of sample_offsets).
  auto ray_at = [&](int x, int y, int s) {
    return static_cast<size_t>((y - y0) * samples + s / samples) * columns +
           static_cast<size_t>((x - x0) * samples + s % samples);
  };
  auto ray = [&](int x, int y, int s) {
    const size_t row = static_cast<size_t>((y - y0) * samples + s / samples);
    return Vec3(base[row] +
                ray_s[static_cast<size_t>((x - x0) * samples + s % samples)] * step[row]);
  };
  auto surface_t = [&](int x, int y, int s) {
    const double t = depth[ray_at(x, y, s)];
    return std::isnan(t) ? std::numeric_limits<double>::infinity() : t;
  };
  const size_t pixels = static_cast<size_t>(width * (y1 - y0));
  on_top.resize(pixels * static_cast<size_t>(ns));
  touched.assign(pixels, 0);
  overlay.trace(x0, y0, x1, y1, ns, ray, surface_t, touched.data(), on_top.data());
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) {
      const size_t pixel = static_cast<size_t>((y - y0) * width + (x - x0));
      if (!touched[pixel]) continue;
      int covered = 0, covered_hits = 0;  // samples the overlay takes, of them surface hits
      Color color = Color::Zero();
      for (int s = 0; s < ns; ++s) {
        const detail::OverlayHit& h = on_top[pixel * static_cast<size_t>(ns) + s];
        if (h.primitive < 0) continue;
        ++covered;
        covered_hits += !std::isnan(depth[ray_at(x, y, s)]);
        color += overlay.shade(h, ray(x, y, s));
      }
      if (covered == 0) continue;
      const int hits = hit_samples[pixel];
      if (hits > covered_hits) color += sums[pixel] * (hits - covered_hits) / hits;
      color += (ns - hits - (covered - covered_hits)) * background;
      // The whole pixel now: its colour over all samples (see the band's output below).
      sums[pixel] = color;
      hit_samples[pixel] = ns;
    }
}

/// The ball that holds the clip volume: parallel rays that miss it need no casting.
struct ClipBall {
  Vec3 centre;
  double radius;
};

/// One row of an orthographic picture's rays, at image row y: parallel rays, each from its
/// own point of the eye's plane (SurfaceRayCaster::begin_parallel_row). Hits go into
/// `current` (after two NaN entries, as the packets' rows) and are shaded at once.
void cast_parallel_row(const View& view, double y, SurfaceRayCaster& caster, bool no_surface,
                       const ClipBall& ball, const std::vector<double>& ray_s,
                       const std::vector<int>& ray_pixel, const std::vector<double>& above,
                       std::vector<double>& current, const detail::Shader& shader, int first_pixel,
                       Color* sums, int* hit_samples, long long& hits, long long& singular) {
  Vec3 origin_base, origin_step;
  view.row_origins(y, origin_base, origin_step);
  // The rays start just before the ball that holds the clip volume rather than at the eye's
  // plane: F is translated to the row's origin, and a nearer origin loses fewer digits to
  // that translation at high degrees. Only t changes, not the points hit.
  const double ahead = (ball.centre - origin_base).dot(view.forward) - 1.01 * ball.radius;
  if (ahead > 0) origin_base += ahead * view.forward;
  double* t = current.data() + 2;
  const double* up = above.data() + 2;
  const int columns = static_cast<int>(current.size()) - 2;
  if (!no_surface) caster.begin_parallel_row(origin_base, origin_step, view.forward);
  for (int c = 0; c < columns; ++c) {
    t[c] = kNoHit;
    if (no_surface) continue;
    const double s = ray_s[static_cast<size_t>(c)];
    const Vec3 to_centre = ball.centre - (origin_base + s * origin_step);
    const Vec3 across = to_centre - to_centre.dot(view.forward) * view.forward;
    if (across.squaredNorm() > ball.radius * ball.radius * (1 + 1e-9)) continue;
    SurfaceHit h;
    if (!caster.intersect_in_row(s, h, guess_from_neighbours(t[c - 1], t[c - 2], up[c], up[c - 1])))
      continue;
    t[c] = h.t;
    ++hits;
    singular += h.singular;
    const int pixel = first_pixel + ray_pixel[static_cast<size_t>(c)];
    const Color color = shader.shade_ray(h.normal, view.forward, h.front);
    sums[pixel] = hit_samples[pixel]++ == 0 ? color : Color(sums[pixel] + color);
  }
}

}  // namespace

Image render_surface(const Surface& surface, const RenderOptions& options, RenderStats* stats,
                     std::stop_token stop) {
  const auto start = std::chrono::steady_clock::now();
  detail::validate(options);
  const View view = View::from_camera(detail::camera_of(surface, options), surface.scene_radius(),
                                      options.width, options.height);
  const detail::Shader shader(options, view);
  const int threads = detail::thread_count(options.threads);
  const std::optional<detail::OverlayScene> overlay =
      detail::make_overlay(options, surface.scene_radius(), view);

  // One caster per worker, built here so that bad input (no clip, missing parameters) is
  // reported before any thread starts. A picture needs the hit far below a pixel, not to
  // 1e-12 of the clipped segment: 1e-9 (about 1e-8 of the scene's size, where a pixel is
  // about 1e-3) saves a Newton step on most rays.
  RaycastOptions cast_options;
  cast_options.roots.refine_tolerance = 1e-9;
  std::vector<SurfaceRayCaster> casters;
  for (int w = 0; w < threads; ++w) casters.emplace_back(surface, view.eye, cast_options);
  // F ≡ 0: every point of the clip is on F = 0 and there is no surface to see. The polynomial
  // path misses every ray (F restricts to the zero polynomial), so only interval arithmetic,
  // which would find "roots" on every ray and draw the clip, asks the survey
  // (docs/architecture.md): every picture of such a field is empty alike, and a polynomial
  // picture does not pay for a survey.
  const bool no_surface =
      !casters.front().is_exact() && survey_field(surface).vanishes_identically();
  const ClipBall clip_ball{surface.bounds().center(), surface.scene_radius()};
  struct Worker {
    long long rays = 0, hits = 0, singular = 0;
    // Hit parameters of the band's previous and current row of rays (NaN: no hit), each
    // after two NaN entries (the neighbours left of the first ray), and per pixel of the band
    // the sum of the colours of the samples that hit and their number.
    std::vector<double> above, current;
    std::vector<Color> sums;
    std::vector<int> hit_samples;
    // With the singular overlay: the band's hit parameters row by row of rays, each row's
    // base and step, and per sample the overlay's hit.
    std::vector<double> depth;
    std::vector<Vec3> row_base, row_step;
    std::vector<detail::OverlayHit> on_top;
    std::vector<std::uint8_t> touched;
    char pad[64];  // keeps the counters of different workers on different cache lines
  };
  std::vector<Worker> workers(static_cast<size_t>(threads));

  const int samples = options.samples;
  const double weight = 1.0 / (samples * samples);
  std::vector<double> offsets;  // of the samples within a pixel, along x and along y
  for (int i = 0; i < samples; ++i) offsets.push_back((i + 0.5) / samples);
  // Every band spans whole rows, so its rays have the same columns: column c is the ray at
  // s = ray_s[c] (image x), in pixel ray_pixel[c]. Three more positions continue the row for
  // the packets of four that start near its end.
  const int columns = options.width * samples;
  std::vector<double> ray_s;
  std::vector<int> ray_pixel;
  for (int c = 0; c < columns + 3; ++c) {
    ray_s.push_back(c / samples + offsets[static_cast<size_t>(c % samples)]);
    ray_pixel.push_back(c / samples);
  }
  Image image(options.width, options.height);
  const detail::GammaTable& gamma = detail::gamma_table();
  std::uint8_t background[3];  // the background's bytes, copied into pixels no ray hits
  gamma.store(background, options.background);
  const bool finished = detail::for_each_tile(
      options.width, options.height, options.width, kBandRows, threads, stop, options.progress,
      [&](int x0, int y0, int x1, int y1, int worker) {
        ZS_ASSERT(x0 == 0 && x1 == options.width);
        SurfaceRayCaster& caster = casters[static_cast<size_t>(worker)];
        Worker& w = workers[static_cast<size_t>(worker)];
        // The band's rays form a grid of samples × samples per pixel, cast row by row.
        const int width = x1 - x0, rows = (y1 - y0) * samples;
        w.above.assign(static_cast<size_t>(columns + 2), kNoHit);
        w.current.assign(static_cast<size_t>(columns + 2), kNoHit);
        w.sums.resize(static_cast<size_t>(width * (y1 - y0)));  // set by a pixel's first hit
        w.hit_samples.assign(w.sums.size(), 0);
        Vec3 base, step;
        ShadeQueue queue;
        SurfaceHit hits[4];  // of a packet of rays
        for (int r = 0; r < rows; ++r) {
          const int row_of_pixels = r / samples;
          const double row_y = y0 + row_of_pixels + offsets[static_cast<size_t>(r % samples)];
          view.row(row_y, base, step);
          if (view.orthographic) {
            cast_parallel_row(view, row_y, caster, no_surface, clip_ball, ray_s, ray_pixel, w.above,
                              w.current, shader, row_of_pixels * width, w.sums.data(),
                              w.hit_samples.data(), w.hits, w.singular);
            w.rays += columns;
            std::swap(w.above, w.current);
            continue;
          }
          caster.begin_row(base, step);
          double s_min, s_max;  // rays outside miss the clip volume
          caster.row_extent(s_min, s_max);
          // The columns whose rays may meet it, [begin, end) (ray_s increases).
          const auto first_ray = ray_s.begin(), last_ray = ray_s.begin() + columns;
          const int begin =
              static_cast<int>(std::lower_bound(first_ray, last_ray, s_min) - first_ray);
          const int end =
              no_surface
                  ? begin
                  : std::max(begin, static_cast<int>(std::upper_bound(first_ray, last_ray, s_max) -
                                                     first_ray));
          double* t = w.current.data() + 2;
          const double* up = w.above.data() + 2;
          std::fill(t, t + begin, kNoHit);
          std::fill(t + end, t + columns, kNoHit);
          Color* sums = &w.sums[static_cast<size_t>(row_of_pixels * width)];
          int* hit_samples = &w.hit_samples[static_cast<size_t>(row_of_pixels * width)];
          // A pixel's colour is the sum of its samples' colours, added in the order cast.
          auto add = [&](int pixel, const Color& color) {
            sums[pixel] = hit_samples[pixel]++ == 0 ? color : Color(sums[pixel] + color);
          };
          // The rays are cast in packets of four (SurfaceRayCaster::prepare_in_row): each hit
          // is found at once, since the next ray's guess depends on it, and the packet's
          // normals and colours are computed together once its rays are cast.
          auto finish_packet = [&](int first) {
            const int bits = caster.packet_hits(hits);
            for (int k = 0; k < 4; ++k) {
              if (!((bits >> k) & 1)) continue;
              const SurfaceHit& h = hits[k];
              const size_t column = static_cast<size_t>(first + k);
              ++w.hits;
              w.singular += h.singular;
              const int q = queue.size++;
              for (int j = 0; j < 3; ++j) {
                queue.n[j][q] = h.normal[j];
                queue.ray[j][q] = std::fma(ray_s[column], step[j], base[j]);
              }
              queue.front[q] = h.front;
              queue.pixel[q] = ray_pixel[column];
              if (queue.size == 4) {
                Color colors[4];
                shader.shade_rays4(queue.n, queue.ray, queue.front, colors);
                for (int j = 0; j < 4; ++j) add(queue.pixel[j], colors[j]);
                queue.size = 0;
              }
            }
          };
          for (int first = begin; first < end; first += 4) {
            // The rays the packet proves to miss need no casting.
            const int misses = caster.prepare_in_row(
                std::span<const double>(&ray_s[static_cast<size_t>(first)], 4));
            for (int c = first; c < std::min(first + 4, end); ++c) {
              if ((misses >> (c - first)) & 1) {
                t[c] = kNoHit;
                continue;
              }
              const RootGuess guess = guess_from_neighbours(t[c - 1], t[c - 2], up[c], up[c - 1]);
              caster.first_hit_in_row(ray_s[static_cast<size_t>(c)], guess, t[c]);
            }
            finish_packet(first);
          }
          // The row's last hits, one by one (the same colours as shade_rays4).
          for (int q = 0; q < queue.size; ++q)
            add(queue.pixel[q],
                shader.shade_ray(Vec3(queue.n[0][q], queue.n[1][q], queue.n[2][q]),
                                 Vec3(queue.ray[0][q], queue.ray[1][q], queue.ray[2][q]),
                                 queue.front[q]));
          queue.size = 0;
          w.rays += columns;
          if (overlay) {
            w.depth.insert(w.depth.end(), t, t + columns);
            w.row_base.push_back(base);
            w.row_step.push_back(step);
          }
          std::swap(w.above, w.current);
        }
        if (overlay) {
          composite_overlay(*overlay, x0, y0, x1, y1, samples, ray_s, options.background, w.depth,
                            w.row_base, w.row_step, w.on_top, w.touched, w.sums, w.hit_samples);
          w.depth.clear();
          w.row_base.clear();
          w.row_step.clear();
        }
        for (int y = y0; y < y1; ++y) {
          std::uint8_t* out = image.pixel(x0, y);
          for (int x = x0; x < x1; ++x, out += 3) {
            const size_t pixel = static_cast<size_t>((y - y0) * width + (x - x0));
            if (const int n = w.hit_samples[pixel]; n > 0) {
              gamma.store(out,
                          (w.sums[pixel] + (samples * samples - n) * options.background) * weight);
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
    for (const SurfaceRayCaster& c : casters) {
      stats->abandoned_rays += c.abandoned_rays();
      stats->accurate_rays += c.accurate_rays();
    }
    stats->threads = threads;
    stats->exact = casters.front().is_exact();
    stats->seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }
  return image;
}

}  // namespace zeroset
