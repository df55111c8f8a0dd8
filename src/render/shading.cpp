#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <exception>
#include <limits>
#include <mutex>
#include <string>
#include <thread>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include "render_detail.h"
#include "zeroset/detail/exception_trap.h"
#include "zeroset/error.h"

namespace zeroset::detail {

Shader::Shader(const RenderOptions& options, const View& view)
    : lights(world_lights(options.lights.empty() ? default_lights() : options.lights, view)),
      front(options.front),
      back(options.back) {
  lit_front_ = light_up(front);
  lit_back_ = light_up(back);
}

Shader::Lit Shader::light_up(const Material& m) const {
  Lit lit;
  lit.ambient = m.ambient * m.diffuse;
  for (const PlacedLight& l : lights) {
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

void Shader::shade_rays4(const double (&n)[3][4], const double (&ray)[3][4],
                         const bool (&is_front)[4], Color (&out)[4]) const {
#if defined(__AVX2__) && defined(__FMA__)
  // Lane by lane the operations of shade_ray, with the skipped terms masked out.
  if (lit_front_.exponent >= 0 && lit_back_.exponent >= 0) {
    const __m256d zero = _mm256_setzero_pd();
    const __m256d front = _mm256_castsi256_pd(_mm256_set_epi64x(
        is_front[3] ? -1 : 0, is_front[2] ? -1 : 0, is_front[1] ? -1 : 0, is_front[0] ? -1 : 0));
    auto pick = [&](double f, double b) {
      return _mm256_blendv_pd(_mm256_set1_pd(b), _mm256_set1_pd(f), front);
    };
    const __m256d nx = _mm256_loadu_pd(n[0]), ny = _mm256_loadu_pd(n[1]),
                  nz = _mm256_loadu_pd(n[2]);
    const __m256d rx = _mm256_loadu_pd(ray[0]), ry = _mm256_loadu_pd(ray[1]),
                  rz = _mm256_loadu_pd(ray[2]);
    const __m256d length =
        _mm256_sqrt_pd(_mm256_fmadd_pd(rz, rz, _mm256_fmadd_pd(ry, ry, _mm256_mul_pd(rx, rx))));
    const __m256d dx = _mm256_div_pd(rx, length), dy = _mm256_div_pd(ry, length),
                  dz = _mm256_div_pd(rz, length);
    __m256d r = pick(lit_front_.ambient.x(), lit_back_.ambient.x());
    __m256d g = pick(lit_front_.ambient.y(), lit_back_.ambient.y());
    __m256d b = pick(lit_front_.ambient.z(), lit_back_.ambient.z());
    const __m256d nd = _mm256_fmadd_pd(nz, dz, _mm256_fmadd_pd(ny, dy, _mm256_mul_pd(nx, dx)));
    auto power = [](__m256d v, int exponent) {
      __m256d highlight = _mm256_set1_pd(1.0);
      for (int e = exponent; e != 0; e >>= 1) {
        if (e & 1) highlight = _mm256_mul_pd(highlight, v);
        v = _mm256_mul_pd(v, v);
      }
      return highlight;
    };
    // Both materials are lit by the same lights, term by term.
    for (size_t i = 0; i < lit_front_.terms.size(); ++i) {
      const Lit::Term &tf = lit_front_.terms[i], &tb = lit_back_.terms[i];
      const __m256d lx = pick(tf.l[0], tb.l[0]), ly = pick(tf.l[1], tb.l[1]),
                    lz = pick(tf.l[2], tb.l[2]);
      const __m256d ndl = _mm256_fmadd_pd(nz, lz, _mm256_fmadd_pd(ny, ly, _mm256_mul_pd(nx, lx)));
      // shade skips a term when ndl <= 0 (not for NaN): keep the lanes where that is false.
      const __m256d lit = _mm256_cmp_pd(ndl, zero, _CMP_NLE_UQ);
      if (_mm256_movemask_pd(lit) == 0) continue;
      r = _mm256_blendv_pd(r, _mm256_fmadd_pd(ndl, pick(tf.diffuse[0], tb.diffuse[0]), r), lit);
      g = _mm256_blendv_pd(g, _mm256_fmadd_pd(ndl, pick(tf.diffuse[1], tb.diffuse[1]), g), lit);
      b = _mm256_blendv_pd(b, _mm256_fmadd_pd(ndl, pick(tf.diffuse[2], tb.diffuse[2]), b), lit);
      const __m256d rv =
          _mm256_fmadd_pd(_mm256_mul_pd(_mm256_set1_pd(-2.0), ndl), nd,
                          _mm256_fmadd_pd(lz, dz, _mm256_fmadd_pd(ly, dy, _mm256_mul_pd(lx, dx))));
      const __m256d shiny = _mm256_and_pd(lit, _mm256_cmp_pd(rv, zero, _CMP_NLE_UQ));
      if (_mm256_movemask_pd(shiny) == 0) continue;
      __m256d highlight = power(rv, lit_front_.exponent);
      if (lit_back_.exponent != lit_front_.exponent)
        highlight = _mm256_blendv_pd(power(rv, lit_back_.exponent), highlight, front);
      r = _mm256_blendv_pd(r, _mm256_fmadd_pd(highlight, pick(tf.specular[0], tb.specular[0]), r),
                           shiny);
      g = _mm256_blendv_pd(g, _mm256_fmadd_pd(highlight, pick(tf.specular[1], tb.specular[1]), g),
                           shiny);
      b = _mm256_blendv_pd(b, _mm256_fmadd_pd(highlight, pick(tf.specular[2], tb.specular[2]), b),
                           shiny);
    }
    double rs[4], gs[4], bs[4];
    _mm256_storeu_pd(rs, r);
    _mm256_storeu_pd(gs, g);
    _mm256_storeu_pd(bs, b);
    for (int i = 0; i < 4; ++i) out[i] = Color(rs[i], gs[i], bs[i]);
    return;
  }
#endif
  for (int i = 0; i < 4; ++i)
    out[i] = shade_ray(Vec3(n[0][i], n[1][i], n[2][i]), Vec3(ray[0][i], ray[1][i], ray[2][i]),
                       is_front[i]);
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
  if (requested < 0 || requested > kMaxThreads)
    throw InvalidArgument("threads", std::to_string(requested),
                          "must lie in [0, " + std::to_string(kMaxThreads) + "] (0: all cores)");
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
  detail::ExceptionTrap trap;
  std::mutex mutex;
  auto work = [&](int worker) {
    for (int t = next++; t < tiles && !trap.failed() && !stop.stop_requested(); t = next++)
      trap.run([&] {
        const int x0 = (t % tx) * tile_width, y0 = (t / tx) * tile_height;
        body(x0, y0, std::min(width, x0 + tile_width), std::min(height, y0 + tile_height), worker);
        const int d = ++done;
        if (progress) {
          std::unique_lock lock(mutex, std::try_to_lock);
          if (lock) progress(static_cast<double>(d) / tiles);
        }
      });
  };
  threads = std::clamp(threads, 1, std::max(1, tiles));
  {
    // jthreads: when starting one fails (no memory for its stack), those started are joined
    // before the exception leaves, instead of std::terminate for a joinable std::thread.
    std::vector<std::jthread> pool;
    for (int w = 1; w < threads; ++w) pool.emplace_back(work, w);
    work(0);
  }
  trap.rethrow();
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
    for (int i = 0; i < samples; ++i) out.emplace_back((i + 0.5) / samples, (j + 0.5) / samples);
  return out;
}

}  // namespace zeroset::detail
