// The singular set drawn over pictures: where it shows, what hides it, and that pictures
// without it stay as they were.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include "render/sphere_shapes.h"
#include "support/equation.h"
#include "zeroset/error.h"
#include "zeroset/render/render.h"
#include "zeroset/render/view.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset {
namespace {

using test::sphere_points;
using test::uv_sphere;

using test::catalog_surface;

RenderOptions small_picture(int size, int samples = 1) {
  RenderOptions o;
  o.width = o.height = size;
  o.samples = samples;
  return o;
}

/// The pixel a world point projects into.
std::pair<int, int> pixel_of(const Surface& s, const RenderOptions& o, const Vec3& p) {
  const View v =
      View::from_camera(o.camera ? *o.camera : s.camera, s.scene_radius(), o.width, o.height);
  double x, y, depth;
  EXPECT_TRUE(v.project(p, x, y, depth));
  return {static_cast<int>(std::floor(x)), static_cast<int>(std::floor(y))};
}

bool is_magenta(const std::uint8_t* p) { return p[0] > p[1] + 60 && p[2] > p[1] + 60; }
bool same_pixel(const Image& a, const Image& b, std::pair<int, int> at) {
  const std::uint8_t *p = a.pixel(at.first, at.second), *q = b.pixel(at.first, at.second);
  return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
}

TEST(SingularOverlay, ShowsWhitneysHandleWhereTheSurfaceIsNot) {
  // x² = y²z has no sheet below z = 0, only the z axis (the handle): the ray caster cannot
  // see it, the overlay draws it in the isolated colour.
  const Surface s = catalog_surface("whitney");
  RenderOptions o = small_picture(120);
  const Image plain = render_surface(s, o);
  o.singular_overlay = SingularOverlay{.set = find_singular_set(s), .tube_radius = 0.03};
  ASSERT_EQ(o.singular_overlay->set.count(CurveKind::kIsolated), 1);
  const Image drawn = render_surface(s, o);
  for (double z : {-0.3, -0.6, -0.9}) {
    const auto at = pixel_of(s, o, Vec3(0, 0, z));
    const std::uint8_t* before = plain.pixel(at.first, at.second);
    EXPECT_EQ(before[0] + before[1] + before[2], 3 * 255) << "z " << z << ": background before";
    EXPECT_TRUE(is_magenta(drawn.pixel(at.first, at.second))) << "z " << z;
  }
}

/// A set with an isolated curve in front of the unit sphere (towards the eye) and a crossing
/// curve and a node inside it, where the sphere hides them.
SingularSet set_around_the_sphere(const View& v) {
  SingularSet set;
  const Vec3 towards_eye = (v.eye - v.target).normalized();
  const Vec3 front = 1.3 * towards_eye;
  set.curves.push_back({CurveKind::kIsolated, {front - 0.4 * v.up, front + 0.4 * v.up}});
  set.curves.push_back({CurveKind::kCrossing, {Vec3(-0.5 * v.right), Vec3(0.5 * v.right)}});
  set.points.push_back({Vec3(0.3 * v.up - 0.4 * v.right), SingularPointKind::kNode});
  return set;
}

/// The three renderers, each drawing the unit sphere.
std::vector<std::pair<std::string, std::function<Image(const RenderOptions&)>>> renderers() {
  const Surface s = catalog_surface("sphere");
  const std::vector<Vec3> points = sphere_points(20000);
  const std::vector<double> radii(points.size(), 0.03);
  const Mesh mesh = uv_sphere(24, 48);
  return {{"surface", [s](const RenderOptions& o) { return render_surface(s, o); }},
          {"points",
           [s, points, radii](const RenderOptions& o) {
             return render_points(s, points, points, radii, o);
           }},
          {"mesh", [s, mesh](const RenderOptions& o) { return render_mesh(s, mesh, o); }}};
}

TEST(SingularOverlay, IsHiddenBehindTheSurfaceAndShowsInFrontOfIt) {
  const Surface s = catalog_surface("sphere");
  for (int samples : {1, 2}) {
    RenderOptions o = small_picture(100, samples);
    const View v = View::from_camera(s.camera, s.scene_radius(), o.width, o.height);
    const SingularSet set = set_around_the_sphere(v);
    for (const auto& [name, render] : renderers()) {
      o.singular_overlay.reset();
      const Image plain = render(o);
      o.singular_overlay = SingularOverlay{.set = set, .tube_radius = 0.04, .point_radius = 0.1};
      const Image drawn = render(o);
      const std::string what = name + ", samples " + std::to_string(samples);
      const auto front = pixel_of(s, o, 1.3 * (v.eye - v.target).normalized());
      EXPECT_TRUE(is_magenta(drawn.pixel(front.first, front.second)))
          << what << ": the curve in front shows";
      EXPECT_TRUE(same_pixel(plain, drawn, pixel_of(s, o, Vec3(0.25 * v.right))))
          << what << ": the curve inside is hidden";
      EXPECT_TRUE(same_pixel(plain, drawn, pixel_of(s, o, set.points[0].position)))
          << what << ": the node inside is hidden";
      int changed = 0;
      for (size_t i = 0; i < plain.rgb.size(); ++i) changed += plain.rgb[i] != drawn.rgb[i];
      EXPECT_GT(changed, 0) << what;
      EXPECT_LT(changed, static_cast<int>(plain.rgb.size()) / 20) << what << ": thin tubes";
    }
  }
}

TEST(SingularOverlay, WithNothingToDrawLeavesThePictureAsItWas) {
  RenderOptions o = small_picture(64, 2);
  for (const auto& [name, render] : renderers()) {
    o.singular_overlay.reset();
    const Image plain = render(o);
    o.singular_overlay = SingularOverlay{};
    EXPECT_EQ(render(o).rgb, plain.rgb) << name;
  }
}

TEST(SingularOverlay, GivesTheSameImageWithAnyNumberOfThreads) {
  const Surface s = catalog_surface("roman");
  RenderOptions o = small_picture(96, 2);
  o.singular_overlay = SingularOverlay{.set = find_singular_set(s)};
  o.threads = 1;
  const Image one = render_surface(s, o);
  o.threads = 3;
  EXPECT_EQ(render_surface(s, o).rgb, one.rgb);
}

TEST(SingularOverlay, RejectsNegativeRadii) {
  const Surface s = catalog_surface("sphere");
  RenderOptions o = small_picture(32);
  o.singular_overlay = SingularOverlay{.set = {}, .tube_radius = -1};
  EXPECT_THROW(render_surface(s, o), InvalidArgument);
  o.singular_overlay = SingularOverlay{.set = {}, .tube_radius = 0, .point_radius = std::nan("")};
  EXPECT_THROW(render_mesh(s, Mesh{}, o), InvalidArgument);
}

TEST(SingularOverlay, ColoursTellTheKindsApart) {
  const SingularOverlay o;
  const Color curves[] = {o.color(CurveKind::kCrossing), o.color(CurveKind::kIsolated),
                          o.color(CurveKind::kDegenerate)};
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) EXPECT_GT((curves[i] - curves[j]).norm(), 0.4) << i << j;
  EXPECT_EQ(o.color(SingularPointKind::kPinch), o.pinch);
  EXPECT_EQ(o.color(SingularPointKind::kDegenerate), o.degenerate_point);
}

}  // namespace
}  // namespace zeroset
