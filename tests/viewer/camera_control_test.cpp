// The GL matrices show exactly what the ray caster's View shows, and the mouse camera stays
// in bounds.
#include <gtest/gtest.h>

#include <random>

#include "camera_control.h"

namespace zeroset::viewer {
namespace {

// The GL matrices of `c`'s view put 100 random points near the target where View::project
// does, inside the depth range; an orthographic view needs no perspective division.
void expect_gl_projects_like_the_view(const Camera& c, int width, int height, unsigned seed) {
  const View v = View::from_camera(c, 3, width, height);
  double near = 0, far = 0;
  depth_range(v, c.target, 3, near, far);
  const Eigen::Matrix4f m = projection_matrix(v, near, far) * view_matrix(v);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-2, 2);
  for (int i = 0; i < 100; ++i) {
    const Vec3 p = c.target + Vec3(u(rng), u(rng), u(rng));
    double x = 0, y = 0, depth = 0;
    ASSERT_TRUE(v.project(p, x, y, depth));
    const Eigen::Vector4f clip = m * Eigen::Vector4f(p.x(), p.y(), p.z(), 1);
    if (v.orthographic) {
      EXPECT_NEAR(clip.w(), 1, 1e-6);
    }
    const double gx = (clip.x() / clip.w() + 1) * 0.5 * width;
    const double gy = (1 - clip.y() / clip.w()) * 0.5 * height;  // GL's y goes up, the image's down
    EXPECT_NEAR(gx, x, 1e-3);
    EXPECT_NEAR(gy, y, 1e-3);
    const double ndc_z = clip.z() / clip.w();
    EXPECT_GT(ndc_z, -1);
    EXPECT_LT(ndc_z, 1);
  }
}

TEST(CameraControl, GlMatricesProjectPointsWhereTheViewDoes) {
  Camera c;
  c.azimuth_deg = 37;
  c.elevation_deg = -20;
  c.distance = 8;
  c.fov_deg = 35;
  c.target = Vec3(0.3, -0.2, 0.5);
  expect_gl_projects_like_the_view(c, 640, 480, 5);
}

TEST(CameraControl, OrthographicGlMatricesProjectPointsWhereTheViewDoes) {
  Camera c;
  c.azimuth_deg = -50;
  c.elevation_deg = 30;
  c.projection = Projection::orthographic;
  c.ortho_height = 2.5;
  c.target = Vec3(0.1, 0.2, -0.3);
  ASSERT_TRUE(View::from_camera(c, 3, 500, 300).orthographic);
  expect_gl_projects_like_the_view(c, 500, 300, 6);
}

TEST(CameraControl, OrthographicZoomChangesTheWindowNotTheDistance) {
  Camera c;
  c.projection = Projection::orthographic;
  c.distance = 7;
  zoom(c, 0.5, 2.0);  // from the fitted window, 2.16 scene radii high
  EXPECT_NEAR(c.ortho_height, 0.5 * 2.16 * 2.0, 1e-12);
  EXPECT_EQ(c.distance, 7);
  zoom(c, 1e-9, 2.0);
  EXPECT_NEAR(c.ortho_height, 0.04, 1e-12);
  zoom(c, 1e9, 2.0);
  EXPECT_NEAR(c.ortho_height, 200, 1e-9);
}

TEST(CameraControl, OrbitNeverPassesOverThePole) {
  Camera c;
  orbit(c, 0, 10000);
  EXPECT_EQ(c.elevation_deg, kMaxElevationDeg);
  orbit(c, 0, -100000);
  EXPECT_EQ(c.elevation_deg, -kMaxElevationDeg);
  orbit(c, 1e6, 0);
  EXPECT_LE(std::abs(c.azimuth_deg), 180);
}

TEST(CameraControl, ZoomStaysWithinReasonableDistances) {
  Camera c;
  zoom(c, 1e-9, 2.0);
  EXPECT_NEAR(c.distance, 0.1, 1e-12);
  zoom(c, 1e9, 2.0);
  EXPECT_NEAR(c.distance, 100, 1e-9);
}

TEST(CameraControl, PanMovesTheTargetAgainstTheMouse) {
  Camera c;
  c.distance = 10;
  const View v = View::from_camera(c, 1, 400, 400);
  const Vec3 before = c.target;
  pan(c, v, 40, 0);  // dragging right moves the picture right: the target goes left
  EXPECT_LT((c.target - before).dot(v.right), 0);
  EXPECT_NEAR((c.target - before).dot(v.up), 0, 1e-12);
}

}  // namespace
}  // namespace zeroset::viewer
