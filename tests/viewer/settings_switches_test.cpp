// Every key of the scene file's "floaters" and "mesh" objects, switched by the `set` command as
// a script or the panel does: the viewer keeps the value (save-scene writes it and a reload
// reads it), the mode's job uses it, and the run still gives a surface. A bad value is refused
// with the scene file's words and changes nothing.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string>

#include "run_frames.h"
#include "settings_values.h"
#include "support/temp_path.h"
#include "viewer_state.h"
#include "zeroset/floaters/settings.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset::viewer {
namespace {

using json = nlohmann::json;
using test::expected_value;
using test::kFloaterValues;
using test::kMeshValues;
using test::run_until;

using zeroset::test::temp_path;

Scene catalog_scene(const std::string& name) {
  return Scene{make_surface(*find_catalog_entry(name)), {}};
}

void expect_every_key_listed(const json& object, const std::map<std::string, std::string>& values,
                             const std::string& name) {
  for (const auto& [key, value] : object.items())
    EXPECT_TRUE(values.count(key)) << name << "." << key << " has no value in this test";
  for (const auto& [key, value] : values)
    EXPECT_TRUE(object.contains(key)) << name << "." << key << " is no scene key";
}

// The final mesh, to compare runs.
struct MeshPrint {
  std::vector<Vec3> positions;
  std::size_t triangles = 0, curves = 0;
  int improver_steps = 0;
  bool sparse = false;
  bool operator==(const MeshPrint&) const = default;
};

MeshPrint settle_mesh(ViewerState& state) {
  EXPECT_TRUE(run_until(
      state, [&] { return state.is_settled(); }, 120));
  const auto frame = state.mesh();
  if (!frame) return {};
  return {frame->mesh.positions, frame->mesh.triangle_count(), frame->mesh.curves.size(),
          frame->improver_steps, frame->polygonize.sparse};
}

TEST(SettingsSwitches, EveryMeshKeyReachesTheMeshJob) {
  expect_every_key_listed(mesh_settings_to_json(MeshSettings{}), kMeshValues, "mesh");
  // Kummer's nodes and Roman's crossing curves, both cut by their clip: every switch changes
  // the mesh of one of them, made by the improver the key belongs to. Every key with the
  // remesher (the default), where the paper improver's own keys change nothing; with the
  // paper's improver, its own keys and those both improvers read.
  const std::set<std::string> both = {"improve", "boundary", "find_singular"};
  std::map<std::string, std::set<std::string>> changed;  // key: the improvers it changed
  for (const char* name : {"kummer", "roman"}) {
    for (const std::string improver : {"remesh", "paper"}) {
      ViewerState state(catalog_scene(name), Mode::kMesh, 1);
      ASSERT_TRUE(state.command("mesh cells=24 improve=40 improver=" + improver));
      const json defaults = state.settings_object("mesh");
      const MeshPrint base = settle_mesh(state);
      ASSERT_GT(base.triangles, 500u) << name;
      for (const auto& [key, value] : kMeshValues) {
        if (improver == "paper" && !is_paper_only_mesh_key(key) && !both.count(key)) continue;
        SCOPED_TRACE(std::string(name) + ", improver " + improver + ": set mesh." + key + " " +
                     value);
        ASSERT_TRUE(state.command("set mesh." + key + " " + value)) << state.status().text;
        EXPECT_EQ(state.settings_object("mesh")[key], expected_value(value));
        const MeshPrint print = settle_mesh(state);
        EXPECT_GT(print.triangles, 100u) << "still a surface";
        if (!(print == base)) changed[key].insert(improver);
        if (improver == "remesh" && is_paper_only_mesh_key(key)) {
          EXPECT_TRUE(print == base) << "the remesher does not read the paper's own keys";
        }
        // Back to the default, by the scene file's value, and to the same mesh as before.
        ASSERT_TRUE(state.command("set mesh." + key + " " + defaults[key].dump()))
            << state.status().text;
        EXPECT_EQ(state.settings_object("mesh"), defaults);
        EXPECT_TRUE(settle_mesh(state) == base) << "the default again gives the same mesh";
      }
    }
  }
  for (const auto& [key, value] : kMeshValues) {
    std::set<std::string> wanted = {"remesh", "paper"};
    if (is_paper_only_mesh_key(key)) wanted.erase("remesh");
    if (!is_paper_only_mesh_key(key) && !both.count(key)) wanted.erase("paper");
    for (const std::string& improver : wanted)
      EXPECT_TRUE(changed[key].count(improver))
          << "mesh." << key << " " << value << " changed no mesh made by improver " << improver;
  }
}

TEST(SettingsSwitches, EveryFloaterKeyReachesTheFloaterJob) {
  expect_every_key_listed(floater_settings_to_json(FloaterOptions{}), kFloaterValues, "floaters");
  ViewerState state(catalog_scene("kummer"), Mode::kFloaters, 1);
  ASSERT_TRUE(state.command("floaters max_count=600 seed=3"));
  for (const auto& [key, value] : kFloaterValues) {
    SCOPED_TRACE("set floaters." + key + " " + value);
    ASSERT_TRUE(state.command("set floaters." + key + " " + value)) << state.status().text;
    EXPECT_EQ(state.settings_object("floaters")[key], expected_value(value));
    // The job runs on with the new options: floaters on F = 0 within their radius.
    const std::size_t steps = state.stats().floater_steps;
    ASSERT_TRUE(run_until(
        state, [&] { return state.stats().floater_steps >= steps + 80; }, 120));
    const ViewerStats st = state.stats();
    EXPECT_GT(st.floater_count, 20u);
    EXPECT_LT(st.median_residual, st.nominal_radius);
    if (key == "max_count") {
      EXPECT_LE(st.floater_count, 700u);
    }
    if (key == "radius") {
      // The restarted job publishes its σ̂ with its first frame, which may come after frames
      // of the job it replaced.
      EXPECT_TRUE(run_until(
          state, [&] { return state.stats().nominal_radius == 0.2; }, 120))
          << state.stats().nominal_radius;
    }
  }
  // save-scene writes every value, and a viewer that loads the file has them.
  const std::string path = temp_path("floaters.json");
  ASSERT_TRUE(state.command("save-scene " + path));
  std::ifstream in(path);
  const json saved = json::parse(in);
  for (const auto& [key, value] : kFloaterValues)
    EXPECT_EQ(saved["floaters"][key], expected_value(value)) << key;
  ViewerState loaded(catalog_scene("sphere"), Mode::kRaytrace, 1);
  ASSERT_TRUE(loaded.command("load " + path)) << loaded.status().text;
  EXPECT_EQ(loaded.settings_object("floaters"), state.settings_object("floaters"));
}

TEST(SettingsSwitches, SaveSceneWritesEveryMeshKeyAndALoadReadsIt) {
  ViewerState state(catalog_scene("sphere"), Mode::kRaytrace, 1);
  for (const auto& [key, value] : kMeshValues)
    ASSERT_TRUE(state.command("set mesh." + key + " " + value)) << state.status().text;
  const std::string path = temp_path("mesh.json");
  ASSERT_TRUE(state.command("save-scene " + path));
  std::ifstream in(path);
  const json saved = json::parse(in);
  for (const auto& [key, value] : kMeshValues)
    EXPECT_EQ(saved["mesh"][key], expected_value(value)) << key;
  ViewerState loaded(catalog_scene("sphere"), Mode::kRaytrace, 1);
  ASSERT_TRUE(loaded.command("load " + path)) << loaded.status().text;
  EXPECT_EQ(loaded.settings_object("mesh"), state.settings_object("mesh"));
}

TEST(SettingsSwitches, BadValuesAreRefusedWithTheSceneFilesWordsAndChangeNothing) {
  struct Bad {
    const char* command;
    const char* words;
  };
  const Bad cases[] = {
      {"set floaters.feedback -1", "set: /floaters/feedback: must lie in [0, 66.6667)"},
      {"set floaters.feedback 1e9", "set: /floaters/feedback: must lie in [0, 66.6667)"},
      {"set floaters.equilibrium_speed -0.5",
       "set: /floaters/equilibrium_speed: must lie in (0, 16.6667]"},
      {"set floaters.estimator_interval 0",
       "set: /floaters/estimator_interval: must lie in [1, 1000]"},
      {"set floaters.estimator_interval 2.5",
       "set: /floaters/estimator_interval: expected a whole"},
      {"set floaters.feedback fast", "set: /floaters/feedback: expected a number"},
      {"set floaters.cos_weight maybe", "set: /floaters/cos_weight: expected true or false"},
      {"set floaters.radius_adapt fast",
       "set: /floaters/radius_adapt: expected wh, curvature, singular or mixed"},
      {"set floaters.max_count 0", "set: /floaters/max_count: must lie in [1, 100000000]"},
      {"set floaters.speed 3", "set: /floaters/speed: unknown key"},
      {"set mesh.grid fine", "set: /mesh/grid: expected auto, dense or sparse"},
      {"set mesh.refine_steps 65", "set: /mesh/refine_steps: must lie in [0, 64]"},
      {"set mesh.refine_steps 1.5", "set: /mesh/refine_steps: expected a whole number"},
      {"set mesh.curvature_weight -1", "set: /mesh/curvature_weight: must lie in [0, 1000]"},
      {"set mesh.boundary loose", "set: /mesh/boundary: expected fix or constrain"},
      {"set mesh.flips sometimes", "set: /mesh/flips: expected true or false"},
      {"set mesh.cells 0", "set: /mesh/cells: must lie in [1, 32768]"},
      {"set mesh.improve sometimes", "set: /mesh/improve: expected auto, off or a number"},
      {"set mesh.max_steps 5", "set: /mesh/max_steps: unknown key"},
      {"set render.samples 4", "expected floaters.KEY or mesh.KEY"},
      {"set floaters 4", "expected floaters.KEY or mesh.KEY"},
      {"set floaters. 4", "expected floaters.KEY or mesh.KEY"},
      {"mesh grid=fine", "mesh: /mesh/grid: expected auto, dense or sparse"},
      {"floaters feedback=-1", "floaters: /floaters/feedback: must lie in [0, 66.6667)"},
  };
  ViewerState state(catalog_scene("kummer"), Mode::kMesh, 1);
  const json before = state.scene().settings;
  for (const Bad& b : cases) {
    EXPECT_FALSE(state.command(b.command)) << b.command;
    EXPECT_TRUE(state.status().is_error) << b.command;
    EXPECT_NE(state.status().text.find(b.words), std::string::npos)
        << b.command << ": " << state.status().text;
    EXPECT_EQ(state.scene().settings, before) << b.command;
  }
  // The live limits stay the viewer's, in its own words.
  EXPECT_FALSE(state.command("set mesh.cells 600"));
  EXPECT_NE(state.status().text.find("the viewer meshes live with 4 to 512 cells"),
            std::string::npos)
      << state.status().text;
}

}  // namespace
}  // namespace zeroset::viewer
