// The SURFER files of examples/surfer open with their look: every file of the folder is read
// as zeroset reads it, rendered, and its background, materials and lights are checked against
// the file's own entries (docs/surfer.md).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "zeroset/render/render.h"
#include "zeroset/render/settings.h"
#include "zeroset/surface/scene.h"

namespace zeroset {
namespace {

/// The file's key=value lines (the gallery's values have no escapes but the name's).
std::map<std::string, std::string> entries(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::map<std::string, std::string> out;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const size_t eq = line.find('=');
    if (eq != std::string::npos) out[line.substr(0, eq)] = line.substr(eq + 1);
  }
  return out;
}

/// A colour entry "r g b" as zeroset's linear colour (SURFER's colours are what the screen
/// shows: gamma 2.2).
Color linear(const std::string& text) {
  std::istringstream in(text);
  double r, g, b;
  in >> r >> g >> b;
  return Color(std::pow(r, 2.2), std::pow(g, 2.2), std::pow(b, 2.2));
}

std::vector<std::filesystem::path> gallery() {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(ZS_SURFER_GALLERY))
    if (e.path().extension() == ".jsurf") files.push_back(e.path());
  return files;
}

TEST(SurferGallery, EveryFileOpensWithItsLook) {
  const auto files = gallery();
  ASSERT_GE(files.size(), 4u);
  for (const auto& path : files) {
    SCOPED_TRACE(path.filename().string());
    const auto file = entries(path);
    const Scene scene = resolve_scene(path.string());
    RenderOptions o;
    ASSERT_TRUE(scene.settings.contains("render"));
    apply_render_settings(scene.settings["render"], o, path.string());
    EXPECT_LT((o.background - linear(file.at("background_color"))).norm(), 1e-9);
    EXPECT_LT((o.front.diffuse - linear(file.at("front_material_color"))).norm(), 1e-9);
    EXPECT_LT((o.back.diffuse - linear(file.at("back_material_color"))).norm(), 1e-9);
    EXPECT_DOUBLE_EQ(o.front.ambient, std::stod(file.at("front_material_ambient_intensity")));
    EXPECT_DOUBLE_EQ(o.back.shininess, std::stod(file.at("back_material_shininess")));
    size_t on = 0;
    for (int i = 0; i < 8; ++i) {
      const auto it = file.find("light_status_" + std::to_string(i));
      on += it != file.end() && it->second == "ON";
    }
    EXPECT_EQ(o.lights.size(), on);
    EXPECT_EQ(scene.surface.camera.is_orthographic(),
              file.at("camera_type") == "ORTHOGRAPHIC_CAMERA");
    EXPECT_NEAR(scene.surface.clip.spheres.at(0).radius,
                std::pow(10.0, std::stod(file.at("scale_factor"))), 1e-9);

    o.width = o.height = 96;
    o.samples = 1;
    RenderStats stats;
    const Image image = render_surface(scene.surface, o, &stats);
    EXPECT_TRUE(stats.exact);
    // The corner shows the background as the file gives it on screen.
    std::istringstream bg(file.at("background_color"));
    for (int c = 0; c < 3; ++c) {
      double v;
      bg >> v;
      EXPECT_NEAR(image.rgb[static_cast<size_t>(c)], 255 * v, 1.0);
    }
    EXPECT_GT(stats.hits, stats.rays / 10) << "the surface fills too little of the picture";
  }
}

}  // namespace
}  // namespace zeroset
