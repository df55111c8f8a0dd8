// The exact ray caster on the record surfaces (many nodes for their degree, up to degree 12):
// every ray of a picture, cast as render_surface casts it (rows, packets of four, each ray
// guided by its neighbours' hits), against the long-double reference restricted to the same
// ray. See docs/rendering.md ("Accuracy").
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <fmt/core.h>

#include "render/ray_reference.h"
#include "render/record_surfaces.h"
#include "render/render_detail.h"
#include "zeroset/render/raycast.h"
#include "zeroset/render/view.h"
#include "zeroset/surface/scene.h"

namespace zeroset {
namespace {

using test::Reference;
using test::ReferenceCaster;

struct Tally {
  long long rays = 0, agree = 0, ambiguous = 0, spurious = 0, missed = 0, off = 0;
  std::string first_disagreement;
  long long decided() const { return rays - ambiguous; }
};

/// Counts the ray's hit at `got` along the unit ray from `origin` (NaN: a miss) against the
/// reference on the clipped segment.
void compare(const Surface& surface, const Vec3& origin, const Vec3& dir, double got,
             ReferenceCaster& ref, Tally& tally, const std::string& where) {
  ++tally.rays;
  double t0 = 0, t1 = 0;
  Reference r;
  if (surface.clip.ray_interval(origin, dir, 0, t0, t1)) r = ref.first_hit(origin, dir, t0, t1);
  if (r.kind == Reference::Kind::kAmbiguous) {
    ++tally.ambiguous;
    return;
  }
  const bool hit = r.kind == Reference::Kind::kHit;
  std::string what;
  if (hit && std::isnan(got)) {
    ++tally.missed;
    what = fmt::format("missed the hit at {:.9g}", r.t);
  } else if (!hit && !std::isnan(got)) {
    ++tally.spurious;
    what = fmt::format("spurious hit at {:.9g}", got);
  } else if (hit && !(std::abs(got - r.t) <= 1e-7 * surface.scene_radius())) {
    ++tally.off;
    what = fmt::format("hit at {:.12g}, the reference at {:.12g}", got, r.t);
  } else {
    ++tally.agree;
  }
  if (!what.empty() && tally.first_disagreement.empty())
    tally.first_disagreement = where + ": " + what;
}

/// An orthographic picture as render_surface casts it: parallel rows whose rays start just
/// before the clip ball, each guided by its neighbours.
void cast_parallel_picture(const Surface& surface, const View& view, ReferenceCaster& ref,
                           Tally& tally) {
  const double radius = surface.scene_radius();
  const Vec3 centre = surface.bounds().center();
  SurfaceRayCaster caster(surface, view.eye);
  std::vector<double> above(static_cast<size_t>(view.width) + 2, NAN), current = above;
  for (int y = 0; y < view.height; ++y) {
    Vec3 origin, origin_step;
    view.row_origins(y + 0.5, origin, origin_step);
    const double ahead = (centre - origin).dot(view.forward) - 1.01 * radius;
    if (ahead > 0) origin += ahead * view.forward;
    caster.begin_parallel_row(origin, origin_step, view.forward);
    double* t = current.data() + 2;
    const double* up = above.data() + 2;
    for (int c = 0; c < view.width; ++c) {
      SurfaceHit h;
      const double s = c + 0.5;
      const RootGuess guess = detail::guess_from_neighbours(t[c - 1], t[c - 2], up[c], up[c - 1]);
      t[c] = caster.intersect_in_row(s, h, guess) ? h.t : NAN;
      compare(surface, origin + s * origin_step, view.forward, t[c], ref, tally,
              fmt::format("orthographic pixel ({}, {})", c, y));
    }
    std::swap(above, current);
  }
}

/// Casts a size × size picture of `surface` from `camera` as render_surface does and compares
/// each ray with the reference. Depths are compared along the unit ray, within 1e-7 of the
/// clip radius.
void cast_picture(const Surface& surface, const Camera& camera, int size, ReferenceCaster& ref,
                  Tally& tally) {
  const double radius = surface.scene_radius();
  const View view = View::from_camera(camera, radius, size, size);
  if (view.orthographic) {
    cast_parallel_picture(surface, view, ref, tally);
    return;
  }
  SurfaceRayCaster caster(surface, view.eye);
  ASSERT_TRUE(caster.is_exact());
  std::vector<double> ray_s(static_cast<size_t>(size) + 4);
  for (int c = 0; c < size + 4; ++c) ray_s[static_cast<size_t>(c)] = c + 0.5;
  std::vector<double> above(static_cast<size_t>(size) + 2, NAN), current = above;
  for (int y = 0; y < size; ++y) {
    Vec3 base, step;
    view.row(y + 0.5, base, step);
    caster.begin_row(base, step);
    double* t = current.data() + 2;
    const double* up = above.data() + 2;
    for (int first = 0; first < size; first += 4) {
      const int misses =
          caster.prepare_in_row(std::span<const double>(&ray_s[static_cast<size_t>(first)], 4));
      for (int c = first; c < std::min(first + 4, size); ++c) {
        t[c] = NAN;
        if ((misses >> (c - first)) & 1) continue;
        const RootGuess guess = detail::guess_from_neighbours(t[c - 1], t[c - 2], up[c], up[c - 1]);
        caster.first_hit_in_row(ray_s[static_cast<size_t>(c)], guess, t[c]);
      }
      SurfaceHit hits[4];
      caster.packet_hits(hits);
    }
    for (int c = 0; c < size; ++c) {
      const Vec3 d = base + ray_s[static_cast<size_t>(c)] * step;
      compare(surface, view.eye, d.normalized(), t[c] * d.norm(), ref, tally,
              fmt::format("pixel ({}, {}) from camera {:.1f},{:.1f}", c, y, camera.azimuth_deg,
                          camera.elevation_deg));
    }
    std::swap(above, current);
  }
}

class RecordRays : public testing::TestWithParam<test::RecordSurface> {};

TEST_P(RecordRays, PicturesAgreeWithTheReference) {
  const test::RecordSurface& rs = GetParam();
  SurfaceOverrides clip;
  clip.clip_specs = rs.clip;
  const Surface surface = resolve_surface(rs.equation, clip);
  ASSERT_TRUE(surface.field.is_polynomial());
  ReferenceCaster ref(surface.field.polynomial());
  std::mt19937 rng(std::hash<std::string>{}(rs.name) & 0xffff);
  std::uniform_real_distribution<double> az(0, 360), el(-60, 60);
  Tally tally;
  for (int k = 0; k < 3; ++k) {
    Camera camera;
    camera.azimuth_deg = az(rng);
    camera.elevation_deg = el(rng);
    // The third picture is orthographic: parallel rows, F translated to each row's origin.
    if (k == 2) camera.projection = Projection::orthographic;
    cast_picture(surface, camera, 64, ref, tally);
  }
  RecordProperty("rays", static_cast<int>(tally.rays));
  RecordProperty("ambiguous", static_cast<int>(tally.ambiguous));
  EXPECT_LT(tally.ambiguous, tally.rays / 20);
  EXPECT_GE(tally.agree, 0.999 * static_cast<double>(tally.decided()))
      << rs.name << ": " << tally.missed << " missed, " << tally.spurious << " spurious, "
      << tally.off << " off of " << tally.decided() << " rays (" << tally.ambiguous
      << " ambiguous); first: " << tally.first_disagreement;
}

INSTANTIATE_TEST_SUITE_P(Records, RecordRays, testing::ValuesIn(test::record_surfaces()),
                         [](const testing::TestParamInfo<test::RecordSurface>& info) {
                           std::string n = info.param.name;
                           for (char& ch : n)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return n;
                         });

}  // namespace
}  // namespace zeroset
