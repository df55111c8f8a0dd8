#include <algorithm>
#include <array>
#include <cstdint>
#include <atomic>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <string>
#include <thread>

#include "render_detail.h"
#include "zeroset/error.h"

namespace zeroset::detail {

std::vector<Light> default_lights() {
  return {
      {.direction = Vec3(-0.45, 0.55, 1.0), .color = Color(0.78, 0.76, 0.72)},
      {.direction = Vec3(0.9, -0.15, 0.5), .color = Color(0.22, 0.24, 0.3)},
      {.direction = Vec3(0.1, 0.9, -0.7), .color = Color(0.25, 0.25, 0.25)},
  };
}

Shader::Shader(const RenderOptions& options, const View& view)
    : front(options.front), back(options.back) {
  const std::vector<Light> rig = options.lights.empty() ? default_lights() : options.lights;
  for (const Light& l : rig) {
    if (!(l.direction.norm() > 0) || !l.direction.allFinite()) continue;
    const Vec3 d = l.follows_camera ? view.camera_to_world(l.direction) : l.direction;
    lights.push_back({d.normalized(), l.color});
  }
  lit_front_ = light_up(front);
  lit_back_ = light_up(back);
}

Shader::Lit Shader::light_up(const Material& m) const {
  Lit lit;
  lit.ambient = m.ambient * m.diffuse;
  for (const WorldLight& l : lights) {
    const Color diffuse = l.color.cwiseProduct(m.diffuse);
    const Color specular = m.specular > 0 ? Color(m.specular * l.color) : Color::Zero();
    lit.terms.push_back({{l.direction.x(), l.direction.y(), l.direction.z()},
                         {diffuse.x(), diffuse.y(), diffuse.z()},
                         {specular.x(), specular.y(), specular.z()}});
  }
  lit.shininess = m.shininess;
  if (m.shininess >= 0 && m.shininess <= 1024 && m.shininess == std::floor(m.shininess))
    lit.exponent = static_cast<int>(m.shininess);
  return lit;
}

const Camera& camera_of(const Surface& surface, const RenderOptions& options) {
  return options.camera ? *options.camera : surface.camera;
}

void validate(const RenderOptions& options) {
  if (options.width <= 0 || options.height <= 0)
    throw InvalidArgument("image size",
                          std::to_string(options.width) + "x" + std::to_string(options.height),
                          "width and height must be positive");
  if (options.width > 32768 || options.height > 32768)
    throw InvalidArgument("image size",
                          std::to_string(options.width) + "x" + std::to_string(options.height),
                          "at most 32768 pixels per side");
  if (options.samples < 1 || options.samples > 16)
    throw InvalidArgument("anti-aliasing samples", std::to_string(options.samples),
                          "must be between 1 and 16 (samples × samples rays per pixel)");
  if (!options.background.allFinite())
    throw InvalidArgument("background", "non-finite", "colour components must be finite");
}

int thread_count(int requested) {
  if (requested > 0) return requested;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

bool for_each_tile(int width, int height, int tile_width, int tile_height, int threads,
                   std::stop_token stop, const std::function<void(double)>& progress,
                   const std::function<void(int, int, int, int, int)>& body) {
  const int tx = (width + tile_width - 1) / tile_width;
  const int ty = (height + tile_height - 1) / tile_height;
  const int tiles = tx * ty;
  std::atomic<int> next{0}, done{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex mutex;
  auto work = [&](int worker) {
    try {
      for (int t = next++; t < tiles; t = next++) {
        if (failed || stop.stop_requested()) return;
        const int x0 = (t % tx) * tile_width, y0 = (t / tx) * tile_height;
        body(x0, y0, std::min(width, x0 + tile_width), std::min(height, y0 + tile_height),
             worker);
        const int d = ++done;
        if (progress) {
          std::unique_lock lock(mutex, std::try_to_lock);
          if (lock) progress(static_cast<double>(d) / tiles);
        }
      }
    } catch (...) {
      std::lock_guard lock(mutex);
      if (!error) error = std::current_exception();
      failed = true;
    }
  };
  threads = std::clamp(threads, 1, std::max(1, tiles));
  std::vector<std::thread> pool;
  for (int w = 1; w < threads; ++w) pool.emplace_back(work, w);
  work(0);
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  if (stop.stop_requested()) return false;
  if (progress) progress(1.0);
  return true;
}

GammaTable::GammaTable() {
  for (int l = 0; l < 255; ++l)
    threshold[static_cast<size_t>(l)] = std::pow((l + 0.5) / 255.0, 2.2);
  threshold[255] = std::numeric_limits<double>::infinity();
  int level = 0;
  for (int i = 0; i <= 4096; ++i) {
    while (i / 4096.0 >= threshold[static_cast<size_t>(level)]) ++level;
    start[static_cast<size_t>(i)] = static_cast<std::uint8_t>(level);
  }
}

const GammaTable& gamma_table() {
  static const GammaTable table;
  return table;
}

void store_linear(Image& image, int x, int y, const Color& c) {
  gamma_table().store(image.pixel(x, y), c);
}

std::vector<Vec2> sample_offsets(int samples) {
  std::vector<Vec2> out;
  for (int j = 0; j < samples; ++j)
    for (int i = 0; i < samples; ++i)
      out.emplace_back((i + 0.5) / samples, (j + 0.5) / samples);
  return out;
}

}  // namespace zeroset::detail
