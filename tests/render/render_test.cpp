#include "zeroset/render/render.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "render/image_masks.h"
#include "render/render_detail.h"
#include "render/sphere_shapes.h"
#include "support/equation.h"
#include "zeroset/error.h"
#include "zeroset/render/raycast.h"
#include "zeroset/render/view.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/jsurf.h"
#include "zeroset/surface/scene.h"

namespace zeroset {
namespace {

using test::count_holes;
using test::intersection_over_union;
using test::sphere_points;
using test::surface_mask;
using test::uv_sphere;

using test::catalog_surface;

RenderOptions small(int size = 160) {
  RenderOptions o;
  o.width = o.height = size;
  return o;
}

TEST(View, ProjectsPointsBackToTheirPixels) {
  Camera cam;
  cam.azimuth_deg = 40;
  cam.elevation_deg = 30;
  const View v = View::from_camera(cam, 2.0, 300, 200);
  for (double x : {0.5, 120.25, 299.5})
    for (double y : {0.5, 77.0, 199.5}) {
      const Vec3 p = v.eye + 7.0 * v.direction(x, y);
      double px, py, depth;
      ASSERT_TRUE(v.project(p, px, py, depth));
      EXPECT_NEAR(px, x, 1e-9);
      EXPECT_NEAR(py, y, 1e-9);
    }
  EXPECT_NEAR(v.up.z() > 0 ? 1 : 0, 1, 0) << "z is up in the image";
  EXPECT_NEAR(v.right.cross(v.up).dot(-v.forward), 1.0, 1e-12) << "right-handed frame";
}

TEST(View, LooksStraightDownWithoutDegenerating) {
  Camera cam;
  cam.elevation_deg = 90;
  const View v = View::from_camera(cam, 1.0, 10, 10);
  EXPECT_TRUE(v.right.allFinite());
  EXPECT_NEAR(v.right.norm(), 1.0, 1e-12);
  EXPECT_NEAR(v.up.dot(v.forward), 0.0, 1e-12);
}

TEST(View, RowsGiveThePixelDirections) {
  Camera cam;
  cam.azimuth_deg = -25;
  cam.elevation_deg = 60;
  const View v = View::from_camera(cam, 1.5, 320, 240);
  for (double y : {0.5, 100.25, 239.5}) {
    Vec3 base, step;
    v.row(y, base, step);
    for (double x : {0.5, 160.0, 319.5})
      EXPECT_LT(((base + x * step).normalized() - v.direction(x, y)).norm(), 1e-15);
  }
}

TEST(Shading, StoresColoursExactlyAsImageSetLinear) {
  // The renderer's table-driven gamma encoding must give the bytes of Image::set_linear.
  Image a(1, 1), b(1, 1);
  for (int i = -10; i <= 70000; ++i) {
    const double v = i / 65536.0;
    const Color c(v, v * v, std::sqrt(std::max(v, 0.0)));
    a.set_linear(0, 0, c);
    detail::store_linear(b, 0, 0, c);
    ASSERT_EQ(a.rgb, b.rgb) << "value " << v;
  }
}

TEST(RenderSurface, DrawsSphereAsDiskOfTheExpectedSize) {
  Surface s = catalog_surface("sphere");
  RenderOptions o = small(200);
  RenderStats stats;
  const Image img = render_surface(s, o, &stats);
  ASSERT_EQ(img.width, 200);
  ASSERT_EQ(img.height, 200);
  EXPECT_EQ(stats.rays, 200 * 200);
  EXPECT_TRUE(stats.exact);
  EXPECT_GE(stats.threads, 1);
  // The unit sphere seen from distance D under vertical fov φ covers a disk of angular
  // radius asin(1/D): its area in pixels follows from the projection.
  const View v = View::from_camera(s.camera, s.scene_radius(), 200, 200);
  const double dist = (v.eye - v.target).norm();
  const double r_px = std::tan(std::asin(1.0 / dist)) / v.tan_half_fov * 100;
  const double expected = std::numbers::pi * r_px * r_px;
  EXPECT_NEAR(static_cast<double>(stats.hits), expected, 0.02 * expected);
  EXPECT_EQ(stats.singular_normals, 0);
}

// The half width, in pixels, of the widest row of the surface's pixels.
double widest_half_row(const Image& img) {
  const auto mask = surface_mask(img, Color(1, 1, 1));
  int widest = 0;
  for (int y = 0; y < img.height; ++y) {
    int n = 0;
    for (int x = 0; x < img.width; ++x) n += mask[static_cast<size_t>(y) * img.width + x];
    widest = std::max(widest, n);
  }
  return 0.5 * widest;
}

TEST(RenderSurface, OrthographicSphereIsADiscOfRadiusOverHeight) {
  for (const double height : {3.0, 5.0}) {
    Surface s = surface_from_equation("x^2 + y^2 + z^2 - 1");
    s.clip = Clip::sphere(1.5);
    s.camera.projection = Projection::orthographic;
    s.camera.ortho_height = height;
    s.camera.distance = 0.5;  // inside the clip: the rays still start outside it
    RenderOptions o = small(200);
    o.samples = 1;
    RenderStats stats;
    const Image img = render_surface(s, o, &stats);
    const double r_px = 1.0 / height * 200;
    EXPECT_NEAR(widest_half_row(img), r_px, 1.0) << height;
    EXPECT_NEAR(std::sqrt(stats.hits / std::numbers::pi), r_px, 1.0) << height;
    EXPECT_TRUE(stats.exact);
    // The view's projection puts the sphere's rim on that circle, at any depth.
    const View v = View::from_camera(s.camera, s.scene_radius(), 200, 200);
    EXPECT_TRUE(v.orthographic);
    double x, y, depth;
    ASSERT_TRUE(v.project(v.target + v.right, x, y, depth));
    EXPECT_NEAR(x, 100 + r_px, 1e-9);
    EXPECT_NEAR(y, 100, 1e-9);
    ASSERT_TRUE(v.project(v.target + v.right + 0.7 * v.forward, x, y, depth));
    EXPECT_NEAR(x, 100 + r_px, 1e-9);
    // Rays are parallel and start in the eye's plane, outside the clip.
    EXPECT_EQ(v.direction(3, 7), v.forward);
    EXPECT_GT((v.origin(100, 100) - v.target).norm(), 1.5);
  }
}

TEST(RenderSurface, OrthographicPictureMatchesPointsOfTheSameView) {
  Surface s = surface_from_equation("x^2 + y^2 + z^2 - 1");
  s.clip = Clip::sphere(1.5);
  s.camera.projection = Projection::orthographic;
  RenderOptions o = small(120);
  o.samples = 1;
  const auto ray = surface_mask(render_surface(s, o), Color(1, 1, 1));
  const auto mesh = surface_mask(render_mesh(s, uv_sphere(48, 96), o, false), Color(1, 1, 1));
  EXPECT_GT(intersection_over_union(ray, mesh), 0.97);
  // A default height fits the clip sphere (radius 1.5): the unit sphere spans 1/(2.16·1.5).
  const double r_px = 1.0 / (2.16 * 1.5) * 120;
  EXPECT_NEAR(widest_half_row(render_surface(s, o)), r_px, 1.0);
}

TEST(RenderSurface, OpensAndDrawsSurferOrthographicFiles) {
  const Scene scene = jsurf_to_scene(
      "#jSurfer\n#Mon Sep 14 13:17:06 CEST 2015\nsurface_parameter_d=0.0\n"
      "surface_parameter_c=0.0\nsurface_parameter_b=0.0\nsurface_parameter_a=0.5\n"
      "camera_height=2.0\ncamera_type=ORTHOGRAPHIC_CAMERA\n"
      "camera_transform=1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0 -1.0 0.0 0.0 0.0 1.0\n"
      "rotation_matrix=1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0\n"
      "scale_factor=0.0\nsurface_equation=x^2+y^2+z^2-(a+b+c+d)^2\n"
      "surface_name=Kugel\\: r \\= a\n",
      "kugel.jsurf");
  RenderOptions o = small(160);
  o.samples = 1;
  const Image img = render_surface(scene.surface, o);
  EXPECT_NEAR(widest_half_row(img), 0.5 / 2.0 * 160, 1.0);  // radius 0.5 in a window 2 high
}

TEST(RenderSurface, ShowsSmoothSurfacesWithoutPinHoles) {
  // Surfaces without nodes have no legitimate one-pixel gaps; a missed root would show as one.
  // (Near a node the background may show between the two cones, so the catalog-wide check
  // is the per-ray comparison in raycast_test.cpp.)
  for (const char* name : {"sphere", "torus", "clebsch"}) {
    const Image img = render_surface(catalog_surface(name), small(240));
    const auto mask = surface_mask(img, Color(1, 1, 1));
    EXPECT_EQ(count_holes(mask, img.width, img.height), 0) << name;
  }
}

TEST(RenderSurface, DrawsBackSidesDarkerThanFrontSides) {
  // Looking into a cut-open sphere: the inside (back side) is visible through the cut.
  Surface s = surface_from_equation("x^2 + y^2 + z^2 - 1");
  s.clip = Clip::sphere(1.5);
  s.clip.add("plane:0,0,1,0.3");
  s.camera.elevation_deg = 70;
  RenderOptions o = small(120);
  o.samples = 1;
  const Image img = render_surface(s, o);
  const std::uint8_t* centre = img.pixel(60, 60);  // looking through the cut at the inside
  const int centre_sum = centre[0] + centre[1] + centre[2];
  const Image front = render_surface(catalog_surface("sphere"), o);
  const std::uint8_t* f = front.pixel(60, 60);
  EXPECT_LT(centre_sum, f[0] + f[1] + f[2]);
  EXPECT_GT(centre[2], centre[0]) << "the default back material is blue";
}

TEST(RenderSurface, AntiAliasingSmoothsTheSilhouette) {
  Surface s = catalog_surface("sphere");
  RenderOptions o = small(100);
  o.samples = 3;
  RenderStats stats;
  const Image img = render_surface(s, o, &stats);
  EXPECT_EQ(stats.rays, 9 * 100 * 100);
  int intermediate = 0;  // silhouette pixels mixing surface and background
  for (int y = 0; y < 100; ++y)
    for (int x = 0; x < 100; ++x) {
      const std::uint8_t* p = img.pixel(x, y);
      const int sum = p[0] + p[1] + p[2];
      intermediate += sum > 600 && sum < 760;
    }
  EXPECT_GT(intermediate, 20);
}

TEST(RenderSurface, RejectsBadOptions) {
  Surface s = catalog_surface("sphere");
  RenderOptions o = small();
  o.width = 0;
  EXPECT_THROW(render_surface(s, o), InvalidArgument);
  o = small();
  o.samples = 0;
  EXPECT_THROW(render_surface(s, o), InvalidArgument);
  Surface unbounded = surface_from_equation("x^2 + y^2 - z^2");
  EXPECT_THROW(render_surface(unbounded, small()), BadInput);
  Surface missing = surface_from_equation("x^2 + y^2 - a");
  missing.clip = Clip::sphere(2);
  EXPECT_THROW(render_surface(missing, small()), BadInput);
}

TEST(RenderSurface, ReturnsEmptyImageWhenStopped) {
  std::stop_source stop;
  stop.request_stop();
  const Image img = render_surface(catalog_surface("kummer"), small(), nullptr, stop.get_token());
  EXPECT_EQ(img.width, 0);
}

TEST(RenderSurface, MatchesCastingEveryPixelOnItsOwn) {
  // The renderer casts rows of rays, each guided by its neighbours' hits; casting every pixel
  // by itself, without any guess, must give the same picture. Only rays that graze the
  // surface, where the first root is ill-conditioned, may come out differently.
  for (const char* name : {"kummer", "barth6", "roman", "cone"}) {
    const Surface s = catalog_surface(name);
    RenderOptions o = small(200);
    o.samples = 1;
    const Image img = render_surface(s, o);
    const View v = View::from_camera(s.camera, s.scene_radius(), o.width, o.height);
    const detail::Shader shader(o, v);
    SurfaceRayCaster caster(s, v.eye);
    Image single(o.width, o.height);
    for (int y = 0; y < o.height; ++y)
      for (int x = 0; x < o.width; ++x) {
        const Vec3 dir = v.direction(x + 0.5, y + 0.5);
        SurfaceHit hit;
        const Color c =
            caster.intersect(dir, hit) ? shader.shade(hit.normal, dir, hit.front) : o.background;
        detail::store_linear(single, x, y, c);
      }
    int differ = 0, far = 0;
    for (size_t i = 0; i < img.rgb.size(); i += 3) {
      int d = 0;
      for (size_t k = 0; k < 3; ++k) d = std::max(d, std::abs(img.rgb[i + k] - single.rgb[i + k]));
      differ += d > 0;
      far += d > 2;
    }
    EXPECT_LE(differ, o.width * o.height / 1000) << name;
    EXPECT_LE(far, o.width * o.height / 4000) << name;
  }
}

TEST(RenderSurface, GivesTheSameImageWithAnyNumberOfThreads) {
  RenderOptions o = small(96);
  o.threads = 1;
  const Image one = render_surface(catalog_surface("barth6"), o);
  o.threads = 3;
  const Image three = render_surface(catalog_surface("barth6"), o);
  EXPECT_EQ(one.rgb, three.rgb);
}

TEST(RenderPoints, CoversTheSameSilhouetteAsTheSurface) {
  const Surface s = catalog_surface("sphere");
  const std::vector<Vec3> p = sphere_points(20000);
  const std::vector<double> radii(p.size(), 0.03);
  const RenderOptions o = small(160);
  const Image disks = render_points(s, p, p, radii, o);
  const Image exact = render_surface(s, o);
  const Color bg = o.background;
  EXPECT_GT(intersection_over_union(surface_mask(disks, bg), surface_mask(exact, bg)), 0.95);
}

TEST(RenderPoints, RejectsMismatchedArrays) {
  const Surface s = catalog_surface("sphere");
  const std::vector<Vec3> p = sphere_points(10);
  const std::vector<double> radii(3, 0.1);
  EXPECT_THROW(render_points(s, p, p, radii, small()), InvalidArgument);
}

TEST(RenderMesh, CoversTheSameSilhouetteAsTheSurface) {
  const Surface s = catalog_surface("sphere");
  const RenderOptions o = small(160);
  const Image mesh = render_mesh(s, uv_sphere(48, 96), o);
  const Image exact = render_surface(s, o);
  const auto mm = surface_mask(mesh, o.background), me = surface_mask(exact, o.background);
  EXPECT_GT(intersection_over_union(mm, me), 0.97);
  // Shaded from ∇F like the exact render: colours agree closely away from the silhouette.
  const std::uint8_t *a = mesh.pixel(80, 80), *b = exact.pixel(80, 80);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(a[k], b[k], 6);
}

TEST(RenderMesh, DrawsWireframeEdges) {
  const Surface s = catalog_surface("sphere");
  const RenderOptions o = small(160);
  const Mesh m = uv_sphere(12, 24);
  const Image plain = render_mesh(s, m, o), wire = render_mesh(s, m, o, true);
  int dark = 0;
  for (size_t i = 0; i < wire.rgb.size(); i += 3) dark += wire.rgb[i] + 60 < plain.rgb[i];
  EXPECT_GT(dark, 500);
}

TEST(RenderMesh, RejectsOutOfRangeIndices) {
  Mesh m;
  m.positions = {Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()};
  m.triangles = {{0, 1, 7}};
  EXPECT_THROW(render_mesh(catalog_surface("sphere"), m, small()), InvalidArgument);
}

TEST(Png, ReadsBackExactlyWhatWasWritten) {
  // Small pictures are compressed in one piece, large ones in bands on several threads.
  const std::string path = testing::TempDir() + "zeroset_png_roundtrip.png";
  for (const auto& [w, h] : {std::pair{1, 1}, {1, 700}, {37, 5}, {900, 700}}) {
    Image img(w, h);
    for (size_t i = 0; i < img.rgb.size(); ++i)
      img.rgb[i] = static_cast<std::uint8_t>((i * 2654435761u >> 13) % 7 == 0 ? i % 251 : 200);
    write_png(img, path);
    const Image back = read_image(path);
    ASSERT_EQ(back.width, w);
    ASSERT_EQ(back.height, h);
    EXPECT_EQ(back.rgb, img.rgb) << w << "x" << h;
  }
  std::remove(path.c_str());
}

}  // namespace
}  // namespace zeroset
