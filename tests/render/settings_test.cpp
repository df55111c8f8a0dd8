#include "zeroset/render/settings.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "zeroset/error.h"

namespace zeroset {
namespace {

using nlohmann::json;

TEST(RenderSettings, RoundTripsThroughJson) {
  RenderOptions o;
  o.width = 640;
  o.height = 480;
  o.samples = 3;
  o.background = Color(0.1, 0.2, 0.3);
  o.front.shininess = 12;
  o.back.diffuse = Color(0.5, 0.25, 0.125);
  o.lights = {{.direction = Vec3(1, 2, 3), .color = Color(0.5, 0.5, 0.5), .follows_camera = false}};
  RenderOptions r;
  apply_render_settings(render_settings_to_json(o), r, "test");
  EXPECT_EQ(r.width, 640);
  EXPECT_EQ(r.height, 480);
  EXPECT_EQ(r.samples, 3);
  EXPECT_TRUE(r.background.isApprox(o.background));
  EXPECT_EQ(r.front.shininess, 12);
  EXPECT_TRUE(r.back.diffuse.isApprox(o.back.diffuse));
  ASSERT_EQ(r.lights.size(), 1u);
  EXPECT_FALSE(r.lights[0].follows_camera);
  EXPECT_TRUE(r.lights[0].direction.isApprox(Vec3(1, 2, 3)));
}

TEST(RenderSettings, ReadsHexColoursAsDisplayValues) {
  RenderOptions r;
  apply_render_settings(json{{"background", "#808080"}}, r, "test");
  EXPECT_NEAR(r.background.x(), std::pow(128.0 / 255.0, 2.2), 1e-12);
  EXPECT_TRUE(parse_display_color("1,1,1", "c").isApprox(Color(1, 1, 1)));
}

TEST(RenderSettings, NamesTheOffendingEntry) {
  RenderOptions r;
  try {
    apply_render_settings(json{{"front", {{"diffuse", "orange"}}}}, r, "scene.json");
    FAIL() << "no exception";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("scene.json: /render/front/diffuse"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(apply_render_settings(json{{"size", {0, 10}}}, r, "s"), BadInput);
  EXPECT_THROW(apply_render_settings(json{{"samples", 2.5}}, r, "s"), BadInput);
  EXPECT_THROW(apply_render_settings(json{{"lightz", json::array()}}, r, "s"), BadInput);
  EXPECT_THROW(apply_render_settings(json{{"lights", {{{"direction", {0, 0, 0}}}}}}, r, "s"),
               BadInput);
  EXPECT_THROW(parse_display_color("#12345", "--background"), InvalidArgument);
  EXPECT_THROW(parse_display_color("1,2", "--background"), InvalidArgument);
}

}  // namespace
}  // namespace zeroset
