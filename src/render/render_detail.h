#pragma once
// Shading and the tile scheduler shared by the surface, point and mesh renderers and the
// POV-Ray export. Private to the render module.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <stop_token>
#include <vector>

#include "zeroset/render/render.h"
#include "zeroset/render/roots.h"
#include "zeroset/render/view.h"

namespace zeroset::detail {

/// Phong shading with world-space lights and front/back materials.
struct Shader {
  std::vector<PlacedLight> lights;  // in world coordinates
  Material front;
  Material back;

  Shader(const RenderOptions& options, const View& view);
  /// Colour of a point with unit normal `n` (facing the viewer) seen along unit ray `dir`.
  /// Inline: it runs once per hit, and a call costs a noticeable part of it.
  Color shade(const Vec3& n, const Vec3& dir, bool is_front) const;
  /// shade(n, ray.normalized(), is_front) with the ray's direction normalized here, the
  /// form the ray caster's rows use.
  Color shade_ray(const Vec3& n, const Vec3& ray, bool is_front) const;

  /// Four hits shaded together: n[k][i] and ray[k][i] are component k of hit i's normal and
  /// ray direction (any length), out[i] its colour. With AVX2 four hits per instruction; the
  /// same bits as shade_ray hit by hit.
  void shade_rays4(const double (&n)[3][4], const double (&ray)[3][4], const bool (&is_front)[4],
                   Color (&out)[4]) const;

 private:
  /// A material under the lights: its ambient colour and, per light, the light's direction
  /// and the colours its diffuse and specular terms scale, side by side in one array.
  struct Lit {
    struct Term {
      double l[3];         // unit direction towards the light
      double diffuse[3];   // light colour × diffuse colour
      double specular[3];  // light colour × specular weight
    };
    Color ambient;
    std::vector<Term> terms;
    double shininess = 0;
    int exponent = -1;  // shininess when it is a whole number up to 1024 (else -1)
  };
  Lit lit_front_, lit_back_;
  Lit light_up(const Material& m) const;
};

// The dot products and sums below are written as fused multiply-adds in a fixed order, the
// order shade_rays4 uses, so that the scalar and the vector code give the same bits.
inline Color Shader::shade(const Vec3& n, const Vec3& dir, bool is_front) const {
  const Lit& m = is_front ? lit_front_ : lit_back_;
  // Plain scalars: Eigen's 3-vector dot products and sums cost several times as much here.
  const double nx = n.x(), ny = n.y(), nz = n.z();
  const double dx = dir.x(), dy = dir.y(), dz = dir.z();
  double r = m.ambient.x(), g = m.ambient.y(), b = m.ambient.z();
  // The reflection 2(n·l)n − l seen from the eye: its dot with −dir is l·dir − 2(n·l)(n·dir).
  const double nd = std::fma(nz, dz, std::fma(ny, dy, nx * dx));
  for (const Lit::Term& t : m.terms) {
    const double ndl = std::fma(nz, t.l[2], std::fma(ny, t.l[1], nx * t.l[0]));
    if (ndl <= 0) continue;
    r = std::fma(ndl, t.diffuse[0], r);
    g = std::fma(ndl, t.diffuse[1], g);
    b = std::fma(ndl, t.diffuse[2], b);
    const double rv =
        std::fma(-2 * ndl, nd, std::fma(t.l[2], dz, std::fma(t.l[1], dy, t.l[0] * dx)));
    if (rv <= 0) continue;
    double highlight;
    if (m.exponent >= 0) {
      // Whole exponents (the usual case) by repeated squaring: several times faster than
      // std::pow, which matters at three lights per pixel.
      highlight = 1;
      double power = rv;
      for (int e = m.exponent; e != 0; e >>= 1) {
        if (e & 1) highlight *= power;
        power *= power;
      }
    } else {
      highlight = std::pow(rv, m.shininess);
    }
    r = std::fma(highlight, t.specular[0], r);
    g = std::fma(highlight, t.specular[1], g);
    b = std::fma(highlight, t.specular[2], b);
  }
  return Color(r, g, b);
}

inline Color Shader::shade_ray(const Vec3& n, const Vec3& ray, bool is_front) const {
  const double length =
      std::sqrt(std::fma(ray.z(), ray.z(), std::fma(ray.y(), ray.y(), ray.x() * ray.x())));
  return shade(n, Vec3(ray.x() / length, ray.y() / length, ray.z() / length), is_front);
}

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

/// The 8-bit output level of linear colour values exactly as Image::set_linear computes it
/// (clamped, gamma 2.2, rounded), through a table of the 255 thresholds between output levels
/// instead of pow. Level L is the output for values in [((L − 0.5)/255)^2.2,
/// ((L + 0.5)/255)^2.2): a table over 4096 equal bins gives the level at each bin's start,
/// and a value then moves up by the thresholds it passes (a few only in the darkest bins,
/// where levels are dense). Immutable once built, so shared by all threads.
struct GammaTable {
  std::array<double, 256> threshold{};  ///< threshold[L]: lowest value of level L + 1
  std::array<std::uint8_t, 4097> start{};
  GammaTable();
  /// Writes the three channels of `c` to p[0..2].
  void store(std::uint8_t* p, const Color& c) const {
    for (int k = 0; k < 3; ++k) {
      const double v = std::clamp(c[k], 0.0, 1.0);  // NaN-free: shading never makes NaN
      int level = start[static_cast<size_t>(v * 4096.0)];
      while (v >= threshold[static_cast<size_t>(level)]) ++level;
      p[k] = static_cast<std::uint8_t>(level);
    }
  }
};
/// The table, built on first use.
const GammaTable& gamma_table();

/// Stores a linear colour at (x, y) exactly as Image::set_linear does (see GammaTable).
void store_linear(Image& image, int x, int y, const Color& c);

/// Where a ray's first hit is expected from its neighbours' hits (pixel coherence): the left
/// neighbour continued by the step from the upper left to the upper neighbour (a plane
/// through the three), or linearly along the row, or the nearest neighbour itself. The
/// spread leaves room for twice the change seen; a guess that is off only costs time.
RootGuess guess_from_neighbours(double left, double left2, double up, double up_left);

/// Offsets (in pixels, within [0, 1)) of the samples × samples stratified samples of a pixel.
std::vector<Vec2> sample_offsets(int samples);

}  // namespace zeroset::detail
