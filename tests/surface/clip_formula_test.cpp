// Clips whose sizes are expressions of the surface's parameters (docs/scenes.md), and the
// Kummer family's clip, which must hold every real node over the whole parameter range
// (docs/singular.md, "The Kummer family").
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "support/refusal.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset {
namespace {

Field field_with(const char* equation, std::initializer_list<std::pair<const char*, double>> q) {
  Field f = compile_field(equation);
  for (const auto& [name, value] : q) f.set_parameter(name, value);
  return f;
}

using test::refusal;

TEST(ClipFormula, SizesFollowTheParameters) {
  Clip c;
  c.add("sphere:3*sqrt(mu)");
  c.add("plane:0,0,1,mu/2");
  c.add("box:-a,-1,-1,2*a,1,1");
  c.add("sphere:10@mu,0,0");
  EXPECT_TRUE(c.is_parametric());
  Field f = field_with("x^2 + y^2 + z^2 - mu - a", {{"mu", 4}, {"a", 0.5}});
  c.update(f);
  ASSERT_EQ(c.spheres.size(), 2u);
  ASSERT_EQ(c.planes.size(), 7u);
  EXPECT_DOUBLE_EQ(c.spheres[0].radius, 6);
  EXPECT_DOUBLE_EQ(c.planes[0].offset, 2);
  EXPECT_EQ(c.planes[0].normal, Vec3::UnitZ());
  EXPECT_TRUE(c.spheres[1].center.isApprox(Vec3(4, 0, 0)));
  EXPECT_NEAR(c.bounds().hi.x(), 1.0, 1e-15);  // the box's x1 = 2a
  EXPECT_NEAR(c.bounds().lo.x(), -0.5, 1e-15);
  f.set_parameter("mu", 9);
  f.set_parameter("a", 2);
  c.update(f);
  EXPECT_DOUBLE_EQ(c.spheres[0].radius, 9);
  EXPECT_DOUBLE_EQ(c.planes[0].offset, 4.5);
  EXPECT_NEAR(c.bounds().hi.x(), 4.0, 1e-15);
  EXPECT_FALSE(c.contains(Vec3(0, 0, 4.6)));
  EXPECT_TRUE(c.contains(Vec3(3.9, 0, 0.1)));
}

TEST(ClipFormula, ConstantSpecsStayPlainNumbers) {
  Clip c;
  c.add("sphere:3");
  c.add("box:-1,-2,-3,1,2,3");
  EXPECT_FALSE(c.is_parametric());
  c.update(Field());  // nothing to do
  EXPECT_EQ(c.spheres[0].radius, 3);
  EXPECT_EQ(c.to_specs().front(), "sphere:3");
  // Constant expressions are expressions too: kept as written.
  Clip e;
  e.add("sphere:2*pi");
  e.update(Field());
  EXPECT_DOUBLE_EQ(e.spheres[0].radius, 2 * M_PI);
  EXPECT_EQ(e.to_specs(), std::vector<std::string>{"sphere:2*pi"});
}

TEST(ClipFormula, SpecsRoundTripAsWritten) {
  Clip c;
  c.add("sphere:2");
  c.add("sphere:(3 + abs(mu - 1))/2");
  c.add("plane:1,0,0,mu");
  const auto specs = c.to_specs();
  ASSERT_EQ(specs.size(), 3u);
  EXPECT_EQ(specs[0], "sphere:2");
  EXPECT_EQ(specs[1], "sphere:(3 + abs(mu - 1))/2");
  EXPECT_EQ(specs[2], "plane:1,0,0,mu");
  Clip again;
  for (const auto& s : specs) again.add(s);
  const Field f = field_with("x - mu", {{"mu", 5}});
  c.update(f);
  again.update(f);
  for (const Vec3& p : {Vec3(1.9, 0, 0), Vec3(0, 2.1, 0), Vec3(1, 1, 1), Vec3(-1.5, 0.5, 0)})
    EXPECT_EQ(c.value(p), again.value(p)) << p.transpose();
}

TEST(ClipFormula, BadExpressionsAreRefusedWithTheirReason) {
  auto add = [](const char* spec) {
    return refusal([&] {
      Clip c;
      c.add(spec);
    });
  };
  EXPECT_NE(add("sphere:3*(mu").find("neither a number nor an expression"), std::string::npos);
  EXPECT_NE(add("sphere:x + 1").find("depends on x, y or z"), std::string::npos);
  EXPECT_NE(add("sphere:mu,1").find("one radius"), std::string::npos);
  EXPECT_NE(add("plane:0,0,mu").find("nx,ny,nz,d"), std::string::npos);
  EXPECT_NE(add("sphere:1e999").find("not a finite number"), std::string::npos);

  auto update = [](const char* spec, double mu) {
    return refusal([&] {
      Clip c;
      c.add(spec);
      c.update(field_with("x - mu", {{"mu", mu}}));
    });
  };
  EXPECT_EQ(update("sphere:mu", 2), "");
  EXPECT_NE(update("sphere:nu", 2).find("'nu' is not a parameter of the surface (it has: mu)"),
            std::string::npos);
  EXPECT_NE(update("sphere:log(mu - 2)", 2).find("not a finite number"), std::string::npos);
  EXPECT_NE(update("sphere:sqrt(mu)", -1).find("not a finite number"), std::string::npos);
  EXPECT_NE(update("sphere:mu - 3", 2).find("positive radius"), std::string::npos);
  EXPECT_NE(update("sphere:mu - 3", 2).find("mu = 2"), std::string::npos);
  EXPECT_NE(update("sphere:mu", 2e7).find("range"), std::string::npos);
  EXPECT_NE(update("box:mu,0,0,mu+1e-12,1,1", 5).find("too small"), std::string::npos);
  // A parameter without a value.
  EXPECT_NE(refusal([] {
              Clip c;
              c.add("sphere:mu");
              c.update(compile_field("x - mu"));
            }).find("has no value"),
            std::string::npos);
}

TEST(ClipFormula, OverridesAndSceneFilesKeepTheExpression) {
  const Surface s = resolve_surface("x^2 + y^2 - z^2 - a",
                                    {.params = {{"a", 4}}, .clip_specs = {"sphere:2*sqrt(a)"}});
  EXPECT_DOUBLE_EQ(s.clip.spheres[0].radius, 4);
  EXPECT_NE(refusal([] {
              resolve_surface("x^2 - a", {.params = {{"a", 1}}, .clip_specs = {"sphere:b"}});
            }).find("'b'"),
            std::string::npos);

  const std::string path =
      (std::filesystem::temp_directory_path() / "zeroset_clip_formula_test.json").string();
  Scene scene = resolve_scene("kummer", {.params = {{"mu", 100}}, .clip_specs = {}});
  write_scene(scene, path);
  const Scene back = read_scene(path);
  EXPECT_EQ(back.surface.clip.to_specs(), scene.surface.clip.to_specs());
  EXPECT_TRUE(back.surface.clip.is_parametric());
  EXPECT_DOUBLE_EQ(back.surface.clip.spheres[0].radius, scene.surface.clip.spheres[0].radius);
  // The file's clip at a parameter value the override gives.
  const Surface at = resolve_surface(path, {.params = {{"mu", 1000}}, .clip_specs = {}});
  EXPECT_NEAR(at.clip.spheres[0].radius, 1.04 * 999, 1e-9);
  // A clip in a file naming a parameter the equation lacks: refused at its pointer.
  std::ofstream(path) << R"({"equation": "x^2 + y^2 + z^2 - a", "parameters": {"a": 1},
                             "clip": ["sphere:2*b"]})";
  EXPECT_NE(refusal([&] { resolve_surface(path); }).find("/clip"), std::string::npos);
  std::filesystem::remove(path);
}

// F and ∇F vanish at p relative to the size of F's terms there.
void expect_node(const Field& f, double mu, const Vec3& p) {
  Evaluator ev(f);
  Vec3 g;
  const double v = ev.value_gradient(p, g);
  const double r2 = p.squaredNorm();
  const double scale = (std::abs(3 - mu) + std::abs(3 * mu - 1)) * std::pow(1 + r2 + mu, 2);
  EXPECT_LE(std::abs(v), 1e-12 * scale) << "mu = " << mu << " at " << p.transpose();
  EXPECT_LE(g.norm() * (1 + std::sqrt(r2)), 1e-10 * scale)
      << "mu = " << mu << " at " << p.transpose();
}

TEST(KummerFamily, TheClipHoldsEveryRealNodeWithAMargin) {
  Surface s = make_surface(*find_catalog_entry("kummer"));
  ASSERT_EQ(s.ranges.size(), 1u);
  EXPECT_NEAR(s.ranges[0].min, 1.0 / 3 + 0.01, 1e-15);
  EXPECT_EQ(s.ranges[0].max, 1.28e6);
  EXPECT_EQ(s.field.parameter_values()[0], 1.5);
  for (double mu : {0.5, 1.02, 2.44, 2.99, 3.01, 10.0, 1000.0, 1.28e6}) {
    s.field.set_parameter("mu", mu);
    s.clip.update(s.field);
    ASSERT_EQ(s.clip.spheres.size(), 1u);
    const double radius = s.clip.spheres[0].radius;
    const auto all = s.singular_points_fn(s.field);
    EXPECT_EQ(all.size(), mu < 1 ? 4u : 16u) << "mu = " << mu;
    double farthest = 0;
    for (const Vec3& p : all) {
      expect_node(s.field, mu, p);
      farthest = std::max(farthest, p.norm());
    }
    // The farthest node: the 12 on the edge lines at sqrt(mu), the 4 on the axes at
    // (sqrt(3)/2)·|mu - 1|.
    EXPECT_NEAR(farthest, std::max(mu > 1 ? std::sqrt(mu) : 0, std::sqrt(3) / 2 * std::abs(mu - 1)),
                1e-9 * (1 + farthest));
    EXPECT_LE(1.2 * farthest, radius) << "mu = " << mu;
    EXPECT_EQ(s.singular_points().size(), all.size()) << "mu = " << mu;
  }
}

TEST(KummerFamily, TheClipIsTheFixedSphereUpToMuThree) {
  Surface s = make_surface(*find_catalog_entry("kummer"));
  for (double mu : {0.35, 1.0, 1.5, 2.44, 3.0, 3.8}) {
    s.field.set_parameter("mu", mu);
    s.clip.update(s.field);
    EXPECT_DOUBLE_EQ(s.clip.spheres[0].radius, 3) << mu;
  }
}

}  // namespace
}  // namespace zeroset
