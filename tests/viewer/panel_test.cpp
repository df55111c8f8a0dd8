// The ImGui panel without a window: random clicks and drags all over it, in every mode, must
// leave the viewer working (no ImGui assertion, no exception, a consistent state).
#include <gtest/gtest.h>
#include <imgui.h>

#include <filesystem>
#include <random>
#include <string>

#include "panel.h"
#include "settings_panel.h"
#include "zeroset/floaters/settings.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/keyframes.h"
#include "zeroset/surface/scene.h"

namespace zeroset::viewer {
namespace {

class Gui {
 public:
  explicit Gui(float height = 800) {
    ImGui::CreateContext();
    ImGuiIO& io = ImGui::GetIO();
    io.IniFilename = nullptr;
    io.DisplaySize = ImVec2(1000, height);
    unsigned char* pixels = nullptr;
    int w = 0, h = 0;
    io.Fonts->GetTexDataAsRGBA32(&pixels, &w, &h);  // builds the font atlas
  }
  ~Gui() { ImGui::DestroyContext(); }

  // One frame with the mouse at (x, y), the left button down or up.
  void frame(ViewerState& state, PanelState& panel, float x, float y, bool down) {
    ImGuiIO& io = ImGui::GetIO();
    io.DeltaTime = 1.0f / 60;
    io.MousePos = ImVec2(x, y);
    io.MouseDown[0] = down;
    ImGui::NewFrame();
    draw_panel(state, panel, io.DisplaySize.y);
    ImGui::Render();
    time_ += 1.0 / 60;
    state.update(time_);
  }

  void click(ViewerState& state, PanelState& panel, float x, float y) {
    frame(state, panel, x, y, false);
    frame(state, panel, x, y, true);
    frame(state, panel, x, y, false);
  }

  void drag(ViewerState& state, PanelState& panel, float x0, float y0, float x1, float y1) {
    frame(state, panel, x0, y0, false);
    for (int k = 0; k <= 4; ++k)
      frame(state, panel, x0 + (x1 - x0) * k / 4, y0 + (y1 - y0) * k / 4, true);
    frame(state, panel, x1, y1, false);
  }

 private:
  double time_ = 0;
};

// A panel whose files (scene, screenshot, mesh, floaters, POV-Ray scene) all go to a
// directory of the test's own under the temporary directory, never to the working directory.
PanelState panel_writing_to(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / name;
  std::filesystem::create_directories(dir);
  PanelState panel;
  panel.scene_path = (dir / "scene.json").string();
  panel.screenshot_path = (dir / "shot.png").string();
  panel.mesh_path = (dir / "mesh.ply").string();
  panel.floaters_path = (dir / "floaters.ply").string();
  panel.pov_path = (dir / "scene.pov").string();
  return panel;
}

TEST(Panel, RandomClicksAndDragsInEveryModeKeepTheViewerWorking) {
  ViewerState state(Scene{make_surface(*find_catalog_entry("kummer")), {}}, Mode::kRaytrace, 2);
  PanelState panel = panel_writing_to("zeroset_panel_test");
  Gui gui;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> x(0, kPanelWidth), y(0, 800), step(-60, 60);
  for (const Mode mode : {Mode::kRaytrace, Mode::kFloaters, Mode::kMesh}) {
    state.set_mode(mode);
    for (int i = 0; i < 1500; ++i) {
      const float x0 = x(rng), y0 = y(rng);
      if (i % 4 == 0) {
        // A drag: moves sliders, scrolls.
        ASSERT_NO_THROW(gui.drag(state, panel, x0, y0, x0 + step(rng), y0 + step(rng)));
      } else {
        ASSERT_NO_THROW(gui.click(state, panel, x0, y0));
      }
      // Whatever was clicked, the surface stays usable.
      ASSERT_TRUE(state.surface().clip.is_bounded());
      ASSERT_EQ(state.surface().ranges.size(), state.surface().field.parameter_names().size());
    }
  }
  EXPECT_NO_THROW(state.view());
  EXPECT_TRUE(state.command("catalog kummer"));
}

// With keyframes the Keyframes section is there too: random clicks add, update, move the time
// of, ease and delete them; whatever happens they stay keyframes `zeroset animate` reads.
TEST(Panel, RandomClicksOnTheKeyframesKeepThemValid) {
  const Scene scene = scene_from_json(nlohmann::json::parse(R"j({
    "equation": "x^2 + y^2 + z^2 - R^2 + a*z^3", "parameters": {"R": 1, "a": 0.1},
    "clip": ["sphere:2"],
    "animation": {"keyframes": [{"time": 0, "params": {"R": 0.8}},
      {"frame": 30, "params": {"R": 1.2}, "camera": {"azimuth_deg": 90}, "ease": "out"},
      {"time": 1, "params": {"a": -0.2}, "camera": {"distance": 7}}]}})j"),
                                      "keys.json");
  ViewerState state(scene, Mode::kRaytrace, 2);
  PanelState panel = panel_writing_to("zeroset_panel_keys");
  Gui gui;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> x(0, kPanelWidth), y(0, 800), step(-60, 60);
  const nlohmann::json before = state.keyframes();
  bool touched = false;
  for (int i = 0; i < 3000; ++i) {
    const float x0 = x(rng), y0 = y(rng);
    if (i % 4 == 0) {
      ASSERT_NO_THROW(gui.drag(state, panel, x0, y0, x0 + step(rng), y0 + step(rng)));
    } else {
      ASSERT_NO_THROW(gui.click(state, panel, x0, y0));
    }
    touched |= state.keyframes() != before || state.keyframe_playhead() != 0;
    if (state.has_keyframes()) {
      ASSERT_NO_THROW((void)read_keyframes(state.scene().settings, state.surface(),
                                           state.keyframe_frames(), "panel"))
          << state.keyframes().dump();
    }
  }
  EXPECT_TRUE(touched) << "the clicks reached the Keyframes section";
}

// A click on every spot of the panel, three keyframes listed each time: Delete on a row that
// is not the last once made the rows below it ask for keyframes no longer there. Bottom up,
// so that no click folds a section above the spots still to come.
TEST(Panel, DeletingAKeyframeFromTheListLeavesTheRowsBelowIntact) {
  const Scene scene = scene_from_json(nlohmann::json::parse(R"j({
    "equation": "x^2 + y^2 + z^2 - R^2", "parameters": {"R": 1}, "clip": ["sphere:2"],
    "animation": {"keyframes": [{"time": 0, "params": {"R": 0.8}},
      {"time": 0.5, "params": {"R": 1.2}}, {"time": 1, "params": {"R": 1}}]}})j"),
                                      "keys.json");
  ViewerState state(scene, Mode::kRaytrace, 2);
  PanelState panel = panel_writing_to("zeroset_panel_rows");
  Gui gui(3000);  // tall enough for every section unscrolled
  int deletions = 0;
  for (float y = 3000; y > 0; y -= 4)
    for (float x = 4; x < kPanelWidth; x += 12) {
      const size_t before = state.keyframes().size();
      ASSERT_NO_THROW(gui.click(state, panel, x, y)) << x << ", " << y;
      if (state.keyframes().size() < before && before == 3) ++deletions;
      // Back to three (Add adds one), at times no keyframe has (a time taken is refused).
      while (state.keyframes().size() > 3) state.delete_keyframe(state.keyframes().size() - 1);
      for (double t = 0.05; state.keyframes().size() < 3 && t < 1; t += 0.1) state.add_keyframe(t);
      ASSERT_EQ(state.keyframes().size(), 3u);
    }
  EXPECT_GT(deletions, 0) << "no click reached a Delete button";
}

// Every key of the scene file's "floaters" and "mesh" objects has exactly one widget with a
// label and a tooltip, and every widget names a key that exists.
TEST(Panel, EverySettingsKeyHasAWidgetWithATooltip) {
  const std::pair<const char*, nlohmann::json> objects[] = {
      {"floaters", floater_settings_to_json(FloaterOptions{})},
      {"mesh", mesh_settings_to_json(MeshSettings{})}};
  for (const auto& [object, keys] : objects) {
    for (const auto& [key, value] : keys.items()) {
      int widgets = 0;
      for (const SettingWidget& w : setting_widgets()) {
        if (w.object != object || w.key != key) continue;
        ++widgets;
        EXPECT_FALSE(w.label.empty()) << object << "." << key;
        EXPECT_GT(w.tooltip.size(), 40u) << object << "." << key << ": say what it does";
      }
      EXPECT_EQ(widgets, 1) << object << "." << key << " needs one widget in settings_panel.cpp";
    }
  }
  for (const SettingWidget& w : setting_widgets()) {
    const bool known =
        (w.object == "floaters" || w.object == "mesh") &&
        (w.object == "floaters" ? objects[0] : objects[1]).second.contains(std::string(w.key));
    EXPECT_TRUE(known) << w.object << "." << w.key << " is no scene key";
  }
}

// What a widget can set is a valid setting: its slider's ends, its choices, both states of a
// switch; each reaches the state as the value the scene file then holds.
TEST(Panel, EveryWidgetsValuesAreAcceptedSettings) {
  ViewerState state(Scene{make_surface(*find_catalog_entry("kummer")), {}}, Mode::kRaytrace, 1);
  const double scene_radius = state.surface().scene_radius();
  for (const SettingWidget& w : setting_widgets()) {
    std::vector<nlohmann::json> values;
    switch (w.kind) {
      case WidgetKind::kSwitch:
        values = {false, true};
        break;
      case WidgetKind::kWhole:
        values = {static_cast<long long>(w.min), static_cast<long long>(w.max)};
        break;
      case WidgetKind::kNumber: {
        const double scale = w.scene_relative ? scene_radius : 1;
        values = {w.min * scale, w.max * scale};
        break;
      }
      case WidgetKind::kChoice: {
        std::string_view rest = w.choices;
        while (!rest.empty()) {
          const size_t bar = rest.find('|');
          values.emplace_back(std::string(rest.substr(0, bar)));
          rest = bar == std::string_view::npos ? std::string_view{} : rest.substr(bar + 1);
        }
        EXPECT_GE(values.size(), 2u) << w.key;
        break;
      }
      case WidgetKind::kImprove:
        values = {false, true, "auto", static_cast<int>(w.max)};
        break;
    }
    for (const nlohmann::json& v : values) {
      const nlohmann::json entry = {{std::string(w.key), v}};
      ASSERT_TRUE(state.set_settings(w.object, entry, "panel"))
          << w.object << "." << w.key << " = " << v.dump() << ": " << state.status().text;
      const nlohmann::json now = state.settings_object(w.object)[std::string(w.key)];
      if (w.kind == WidgetKind::kImprove && v == "auto")
        EXPECT_EQ(now, true) << w.key;  // the scene file's "improve": true
      else
        EXPECT_EQ(now, v) << w.object << "." << w.key;
    }
  }
}

}  // namespace
}  // namespace zeroset::viewer
