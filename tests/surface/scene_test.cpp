#include "zeroset/surface/scene.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "support/temp_path.h"
#include "zeroset/error.h"

namespace zeroset {
namespace {

using zeroset::test::temp_path;

// A scene zeroset could not read back (over json_read::kMaxBytes) is refused before anything
// is written; the old file stays.
TEST(Scene, ASceneTooLargeToReadBackIsNotWritten) {
  const std::string path = temp_path("too-large-scene.json");
  std::ofstream(path) << "old";
  Scene scene = resolve_scene("kummer");
  scene.settings["note"] = std::string((std::size_t{32} << 20) + 1, 'a');
  try {
    write_scene(scene, path);
    ADD_FAILURE() << "a scene of more than 32 MiB was written";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("more than a scene file may be (32 MiB)"),
              std::string::npos)
        << e.what();
  }
  std::ifstream in(path);
  std::string text;
  std::getline(in, text);
  EXPECT_EQ(text, "old");
  scene.settings.erase("note");
  write_scene(scene, path);
  EXPECT_EQ(read_scene(path).surface.label(), scene.surface.label());
}

TEST(Scene, ResolvesCatalogNamesWithDefaults) {
  const Surface s = resolve_surface("kummer");
  EXPECT_EQ(s.name, "kummer");
  EXPECT_DOUBLE_EQ(s.field.parameter_values()[0], 1.5);
  EXPECT_EQ(s.singular_points().size(), 16u);
}

TEST(Scene, AppliesParameterAndClipOverrides) {
  const Surface s =
      resolve_surface("kummer", {.params = {{"mu", 2.0}}, .clip_specs = {"sphere:2.5"}});
  EXPECT_DOUBLE_EQ(s.field.parameter_values()[0], 2.0);
  ASSERT_EQ(s.clip.spheres.size(), 1u);
  EXPECT_DOUBLE_EQ(s.clip.spheres[0].radius, 2.5);
}

TEST(Scene, AClipAwayFromTheCameraTargetBecomesTheTarget) {
  // A close-up clip away from the origin: the camera looks at it, not at the empty origin.
  const Surface s = resolve_surface("roman", {.params = {}, .clip_specs = {"sphere:0.15@0.5,0,0"}});
  EXPECT_NEAR((s.camera.target - Vec3(0.5, 0, 0)).norm(), 0.0, 1e-12);
  // A clip that still holds the target leaves the camera alone.
  const Surface t = resolve_surface("kummer", {.params = {}, .clip_specs = {"sphere:2@0.5,0,0"}});
  EXPECT_EQ(t.camera.target, resolve_surface("kummer").camera.target);
}

TEST(Scene, ResolvesEquationsAndNamesEveryMissingParameter) {
  EXPECT_NO_THROW(resolve_surface("x^2 + y^2 = z^2"));
  try {
    resolve_surface("a*x^2 + b*y^2 - mu");
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    const std::string m = e.what();
    for (const char* name : {"a", "b", "mu"}) EXPECT_NE(m.find(name), std::string::npos) << m;
  }
}

TEST(Scene, UnknownParameterOverrideSaysWhichExist) {
  try {
    resolve_surface("kummer", {.params = {{"nu", 2.0}}, .clip_specs = {}});
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("mu"), std::string::npos) << e.what();
  }
}

TEST(Scene, ReportsAMisspelledCatalogName) {
  try {
    resolve_surface("kumer");
    ADD_FAILURE();
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("did you mean 'kummer'"), std::string::npos) << e.what();
  }
}

TEST(Scene, RoundTripsThroughAFile) {
  Scene scene = resolve_scene("torus", {.params = {{"r", 0.3}}, .clip_specs = {}});
  scene.surface.camera.azimuth_deg = 12;
  scene.settings["render"] = {{"samples", 3}};
  const std::string path = temp_path("roundtrip.json");
  write_scene(scene, path);
  const Scene back = resolve_scene(path);
  EXPECT_EQ(back.surface.field.source(), scene.surface.field.source());
  EXPECT_DOUBLE_EQ(back.surface.field.parameter_values()[scene.surface.field.parameter_index("r")],
                   0.3);
  EXPECT_DOUBLE_EQ(back.surface.camera.azimuth_deg, 12);
  EXPECT_EQ(back.settings["render"]["samples"], 3);
  EXPECT_EQ(back.surface.clip.spheres.size(), 1u);
  std::filesystem::remove(path);
}

TEST(Scene, RoundTripsAnOrthographicCamera) {
  Scene scene = resolve_scene("sphere");
  scene.surface.camera.projection = Projection::orthographic;
  scene.surface.camera.ortho_height = 3.25;
  const std::string path = temp_path("ortho.json");
  write_scene(scene, path);
  const Scene back = resolve_scene(path);
  EXPECT_EQ(back.surface.camera.projection, Projection::orthographic);
  EXPECT_DOUBLE_EQ(back.surface.camera.ortho_height, 3.25);
  write_scene(back, path);  // and once more: the file's own output reads the same
  EXPECT_DOUBLE_EQ(resolve_scene(path).surface.camera.ortho_height, 3.25);
  // Perspective files say nothing of it, and read back as perspective.
  write_scene(resolve_scene("sphere"), path);
  EXPECT_EQ(resolve_scene(path).surface.camera.projection, Projection::perspective);
  std::filesystem::remove(path);
}

TEST(Scene, CatalogSceneKeepsItsSingularPoints) {
  const std::string path = temp_path("kummer.json");
  write_scene(resolve_scene("kummer"), path);
  EXPECT_EQ(resolve_surface(path).singular_points().size(), 16u);
  std::filesystem::remove(path);
}

TEST(Scene, BadFilesSayWhatAndWhere) {
  const std::string path = temp_path("bad.json");
  auto expect_error = [&](const std::string& text, const std::string& where) {
    std::ofstream(path) << text;
    try {
      resolve_surface(path);
      ADD_FAILURE() << text;
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find(where), std::string::npos) << e.what();
    }
  };
  expect_error("{ not json", "not valid JSON");
  expect_error(R"({"equation": 3})", "/equation");
  expect_error(R"({"equation": "x^2 +"})", "/equation");
  expect_error(R"({"equation": "x - a", "parameters": {"a": "big"}})", "/parameters/a");
  expect_error(R"({"equation": "x - a", "parameters": {"b": 1}})", "/parameters/b");
  expect_error(R"({"equation": "x", "clip": ["sphere:-2"]})", "/clip/0");
  expect_error(R"({"equation": "x", "camera": {"fov_deg": 400}})", "/camera/fov_deg");
  expect_error(R"({"equation": "x", "camera": {"azimuth": 30}})", "/camera/azimuth: unknown key");
  expect_error(R"({"equation": "x - a", "parameters": {"a": {"val": 1}}})",
               "/parameters/a/val: unknown key");
  expect_error(R"({"equation": "x - a", "parameters": {"a": 1e999}})", "not valid JSON");
  expect_error(R"([1, 2])", "JSON object");
  expect_error(R"({"equation": "x", "camera": {"projection": "fisheye"}})",
               "/camera/projection: expected \"perspective\" or \"orthographic\"");
  expect_error(R"({"equation": "x", "camera": {"projection": 3}})", "/camera/projection");
  expect_error(R"({"equation": "x", "camera": {"ortho_height": -1}})", "/camera/ortho_height");
  expect_error(R"({"equation": "x", "camera": {"ortho_height": 1e300}})", "/camera/ortho_height");
  expect_error(R"({"equation": "x", "camera": {"ortho_height": "big"}})", "/camera/ortho_height");
  std::filesystem::remove(path);
  try {
    resolve_surface(temp_path("missing.json"));
    ADD_FAILURE();
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.json"), std::string::npos);
  }
}

}  // namespace
}  // namespace zeroset

namespace zeroset {
namespace {

TEST(Scene, BoundedEquationsGetADefaultClipThatHoldsTheSurface) {
  const Surface s = resolve_surface("x^2 + y^2 + z^2 - 4");
  ASSERT_EQ(s.clip.spheres.size(), 1u);
  EXPECT_GE(s.clip.spheres[0].radius, 2.0);
  EXPECT_LE(s.clip.spheres[0].radius, 4.0);
  const Surface t = resolve_surface("(x^2+y^2+z^2+0.8)^2 - 4*(x^2+y^2)");  // a torus
  ASSERT_EQ(t.clip.spheres.size(), 1u);
  EXPECT_GE(t.clip.spheres[0].radius, 1 + std::sqrt(0.2));  // outer equator of the tube
}

TEST(Scene, UnboundedEquationsGetNoDefaultClip) {
  EXPECT_TRUE(resolve_surface("x^2 + y^2 - z^2").clip.is_empty_spec());
  EXPECT_TRUE(resolve_surface("x*y*z - 1").clip.is_empty_spec());
  EXPECT_TRUE(resolve_surface("x^2 + y^2 - 1").clip.is_empty_spec());  // a cylinder
  EXPECT_TRUE(resolve_surface("x^4 + (y - z)^4 - 1").clip.is_empty_spec());
  EXPECT_TRUE(resolve_surface("sin(x) + y").clip.is_empty_spec());
  EXPECT_THROW((void)resolve_surface("x^2 + y^2 - z^2").bounds(), BadInput);
}

}  // namespace
}  // namespace zeroset
