#include "zeroset/surface/clip.h"

#include <gtest/gtest.h>

#include <random>

#include "zeroset/error.h"

namespace zeroset {
namespace {

TEST(Clip, SphereProjectsRadiallyTowardsItsCentre) {
  const Clip c = Clip::sphere(2, Vec3(1, 0, 0));
  const Vec3 q = c.project(Vec3(5, 3, 0));
  EXPECT_NEAR((q - Vec3(1, 0, 0)).norm(), 2, 1e-12);
  EXPECT_NEAR((q - Vec3(1, 0, 0)).normalized().dot(Vec3(4, 3, 0).normalized()), 1, 1e-12);
  EXPECT_EQ(c.project(Vec3(1.5, 0, 0)), Vec3(1.5, 0, 0));
}

TEST(Clip, HalfSpaceProjectsOrthogonally) {
  Clip c;
  c.add("plane:0,0,2,2");  // z <= 1
  const Vec3 q = c.project(Vec3(0.3, -0.2, 4));
  EXPECT_NEAR(q.z(), 1, 1e-12);
  EXPECT_NEAR(q.x(), 0.3, 1e-12);
  EXPECT_NEAR(q.y(), -0.2, 1e-12);
}

TEST(Clip, ProjectionOfABoxCornerLandsOnTheBox) {
  const Clip c = Clip::box(Box3::cube(1));
  const Vec3 q = c.project(Vec3(3, -4, 5));
  EXPECT_TRUE(c.contains(q, 1e-12));
  EXPECT_NEAR(std::abs(c.value(q)), 0, 1e-12);
}

TEST(Clip, ValueIsNegativeInsideZeroOnBoundaryWithUnitGradient) {
  Clip c = Clip::sphere(1);
  c.add("plane:1,0,0,0.5");
  Vec3 g;
  EXPECT_LT(c.value_gradient(Vec3(0, 0, 0), g), 0);
  EXPECT_NEAR(c.value_gradient(Vec3(0.5, 0.1, 0), g), 0, 1e-15);
  EXPECT_TRUE(g.isApprox(Vec3(1, 0, 0)));
  EXPECT_NEAR(c.value_gradient(Vec3(0, 0, 2), g), 1, 1e-15);
  EXPECT_TRUE(g.isApprox(Vec3(0, 0, 1)));
}

TEST(Clip, RayIntervalMatchesContainmentAlongRandomRays) {
  Clip c = Clip::sphere(1.5);
  c.add("plane:0,0,1,1");
  c.add("plane:1,1,0,0.8");
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < 500; ++i) {
    const Vec3 o = 4 * Vec3(u(rng), u(rng), u(rng));
    const Vec3 d = Vec3(u(rng), u(rng), u(rng)).normalized();
    double t0, t1;
    const bool hit = c.ray_interval(o, d, 0, t0, t1);
    for (int k = 0; k <= 200; ++k) {
      const double t = 10.0 * k / 200;
      const bool inside = c.contains(o + t * d);
      const bool in_interval = hit && t >= t0 - 1e-12 && t <= t1 + 1e-12;
      if (std::abs(c.value(o + t * d)) > 1e-9) {
        EXPECT_EQ(inside, in_interval) << i << " t=" << t;
      }
    }
  }
}

TEST(Clip, ParsesSpecsAndRoundTrips) {
  Clip c;
  c.add("sphere:3");
  c.add("sphere:1.5@0,0,0.2");
  c.add("box:2");
  c.add("plane:0,0,-1,0");
  EXPECT_EQ(c.spheres.size(), 2u);
  EXPECT_EQ(c.planes.size(), 7u);
  Clip d;
  for (const auto& s : c.to_specs()) d.add(s);
  ASSERT_EQ(d.planes.size(), c.planes.size());
  for (size_t i = 0; i < c.planes.size(); ++i)
    EXPECT_TRUE(d.planes[i].normal.isApprox(c.planes[i].normal));
}

TEST(Clip, RejectsMalformedSpecsWithTheSpecInTheMessage) {
  for (const char* bad : {"sphere", "sphere:", "sphere:-1", "sphere:1+", "cube:2", "box:1,2",
                          "plane:0,0,0,1", "sphere:1@1,2", "box:1,1,1,0,0,0", "sphere:nan"}) {
    Clip c;
    try {
      c.add(bad);
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find(bad), std::string::npos) << e.what();
    }
  }
}

TEST(Clip, UnboundedClipHasNoBoundsAndSaysHowToFixIt) {
  Clip c;
  c.add("plane:0,0,1,1");
  EXPECT_FALSE(c.is_bounded());
  try {
    (void)c.bounds();
    ADD_FAILURE();
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("--clip sphere"), std::string::npos);
  }
  EXPECT_TRUE(Clip::box(Box3::cube(1)).is_bounded());
}

// A clip has at most kMaxClipParts parts; a box counts six. Beyond, the spec is refused with
// the limit named (every stage tests every part at every point it looks at).
TEST(Clip, PartsAreLimited) {
  Clip c;
  for (std::size_t k = 0; k + 6 < kMaxClipParts; ++k) c.add("sphere:2");
  c.add("box:1");
  EXPECT_EQ(c.spheres.size() + c.planes.size(), kMaxClipParts);
  try {
    c.add("plane:0,0,1,0");
    FAIL() << "the part beyond the limit was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("at most 256 parts"), std::string::npos) << e.what();
  }
  EXPECT_EQ(c.spheres.size() + c.planes.size(), kMaxClipParts);  // unchanged
  Clip d;
  for (std::size_t k = 0; k + 5 < kMaxClipParts; ++k) d.add("sphere:2");
  EXPECT_THROW(d.add("box:1"), InvalidArgument);
}

}  // namespace
}  // namespace zeroset
