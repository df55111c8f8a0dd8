// One rule per setting: the command line, a scene file (read by the command line and by the
// viewer) and a viewer command refuse the same bad value with the same words. Where the viewer
// keeps a tighter live limit, it says so in its own words, for commands and scene files alike.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "support/run_command.h"
#include "support/temp_path.h"
#include "viewer_state.h"
#include "zeroset/error.h"
#include "zeroset/floaters/settings.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/render/settings.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset::viewer {
namespace {

using zeroset::test::temp_path;

Scene sphere_scene() { return Scene{make_surface(*find_catalog_entry("sphere")), {}}; }

// A bad value as each entry point takes it.
struct BadValue {
  const char* cli;       ///< `zeroset` arguments (the surface is "sphere"); "" when no flag sets it
  const char* settings;  ///< the scene file's settings objects
  const char* pointer;   ///< the JSON pointer the scene file's message names
  const char* command;   ///< viewer command; "" when the viewer has none for it
  const char* why;       ///< the words every entry point gives
};

const BadValue kBadValues[] = {
    // floaters
    {"sample sphere --radius -1", R"({"floaters": {"radius": -1}})", "/floaters/radius",
     "floaters radius=-1", "must be a length in [0, 2e+06] (0: chosen from the surface's area)"},
    {"sample sphere --radius 3e6", R"({"floaters": {"radius": 3e6}})", "/floaters/radius",
     "floaters radius=3e6", "must be a length in [0, 2e+06]"},
    {"sample sphere --max-count 0", R"({"floaters": {"max_count": 0}})", "/floaters/max_count",
     "floaters max_count=0", "must lie in [1, 100000000]"},
    {"sample sphere --max-count 200000000", R"({"floaters": {"max_count": 200000000}})",
     "/floaters/max_count", "floaters max_count=200000000", "must lie in [1, 100000000]"},
    {"sample sphere --seed-count 200000000", R"({"floaters": {"seed_count": 200000000}})",
     "/floaters/seed_count", "floaters seed_count=200000000", "must lie in [0, 100000000]"},
    {"sample sphere --seed 100000000000000000", R"({"floaters": {"seed": 1e17}})", "/floaters/seed",
     "floaters seed=100000000000000000", "must lie in [0, 9007199254740992]"},
    {"sample sphere --grading -0.5", R"({"floaters": {"radius_grading": -0.5}})",
     "/floaters/radius_grading", "floaters radius_grading=-0.5", "must lie in [0, 1000] (0: off)"},
    {"sample sphere --grading 1e9", R"({"floaters": {"radius_grading": 1e9}})",
     "/floaters/radius_grading", "floaters radius_grading=1e9", "must lie in [0, 1000] (0: off)"},
    {"sample sphere --radius-adapt fast", R"({"floaters": {"radius_adapt": "fast"}})",
     "/floaters/radius_adapt", "floaters radius_adapt=fast",
     "expected wh, curvature, singular or mixed"},
    // mesh
    {"mesh sphere --resolution 0", R"({"mesh": {"cells": 0}})", "/mesh/cells", "mesh cells=0",
     "must lie in [1, 32768]"},
    {"mesh sphere --resolution 40000", R"({"mesh": {"cells": 40000}})", "/mesh/cells",
     "mesh cells=40000", "must lie in [1, 32768]"},
    {"mesh sphere --improve sometimes", R"({"mesh": {"improve": "sometimes"}})", "/mesh/improve",
     "mesh improve=sometimes", "expected auto, off or a number of steps from 0 to 100000"},
    {"mesh sphere --improve 200000", R"({"mesh": {"improve": 200000}})", "/mesh/improve",
     "mesh max_steps=200000", "expected auto, off or a number of steps from 0 to 100000"},
    {"mesh sphere --boundary loose", R"({"mesh": {"boundary": "loose"}})", "/mesh/boundary",
     "mesh boundary=loose", "expected fix or constrain"},
    {"mesh sphere --grid fine", R"({"mesh": {"grid": "fine"}})", "/mesh/grid", "mesh grid=fine",
     "expected auto, dense or sparse"},
    {"mesh sphere --refine-steps 65", R"({"mesh": {"refine_steps": 65}})", "/mesh/refine_steps",
     "set mesh.refine_steps 65", "must lie in [0, 64]"},
    {"mesh sphere --curvature-weight -1", R"({"mesh": {"curvature_weight": -1}})",
     "/mesh/curvature_weight", "mesh curvature_weight=-1", "must lie in [0, 1000]"},
    {"mesh sphere --curvature-weight 1e4", R"({"mesh": {"curvature_weight": 1e4}})",
     "/mesh/curvature_weight", "set mesh.curvature_weight 1e4", "must lie in [0, 1000]"},
    // render (the viewer's colours are the "viewer" object's; size and samples are the
    // command line's and the "render" object's only)
    {"render sphere --front 1.5,0,0", R"({"render": {"front": {"diffuse": [1.5, 0, 0]}}})",
     "/render/front/diffuse", "color front 1.5 0 0", "components must lie in [0, 1]"},
    {"", R"({"viewer": {"background": [0, 2, 0]}})", "/viewer/background", "color background 0 2 0",
     "components must lie in [0, 1]"},
    {"render sphere --aa 0", R"({"render": {"samples": 0}})", "/render/samples", "",
     "must lie in [1, 16]"},
    {"render sphere --aa 17", R"({"render": {"samples": 17}})", "/render/samples", "",
     "must lie in [1, 16]"},
    {"render sphere --size 40000x10", R"({"render": {"size": [40000, 10]}})", "/render/size", "",
     "width and height must lie in [1, 32768]"},
    {"render sphere --size 20000x20000", R"({"render": {"size": [20000, 20000]}})", "/render/size",
     "", "must have at most 100000000 pixels"},
    // camera (the command line's --camera and --fov, the scene's "camera" object)
    {"render sphere --camera 0,100", R"({"camera": {"elevation_deg": 100}})",
     "/camera/elevation_deg", "camera 0 100", "must lie in [-90, 90] degrees"},
    {"sample sphere --camera 0,-91", R"({"camera": {"elevation_deg": -91}})",
     "/camera/elevation_deg", "camera 0 -91", "must lie in [-90, 90] degrees"},
    {"render sphere --camera 0,10,-1", R"({"camera": {"distance": -1}})", "/camera/distance",
     "camera 0 10 -1", "must lie in [0, 1e+12] (0: fit the clip volume)"},
    {"render sphere --camera 0,10,1e300", R"({"camera": {"distance": 1e300}})", "/camera/distance",
     "camera 0 10 1e300", "must lie in [0, 1e+12] (0: fit the clip volume)"},
    {"render sphere --fov 175", R"({"camera": {"fov_deg": 175}})", "/camera/fov_deg", "",
     "must lie in [1, 170] degrees"},
    {"render sphere --fov 0.5", R"({"camera": {"fov_deg": 0.5}})", "/camera/fov_deg", "",
     "must lie in [1, 170] degrees"},
};

// The scene file for `settings`: the sphere with those settings objects.
std::string write_scene_file(const std::string& settings, int index) {
  nlohmann::json j = nlohmann::json::parse(settings);
  j["name"] = "sphere";
  const std::string path = temp_path("scene" + std::to_string(index) + ".json");
  std::ofstream(path) << j.dump();
  return path;
}

// The output flag that makes a subcommand run.
std::string output_for(const std::string& cli) {
  if (cli.rfind("sample", 0) == 0) return " -o " + temp_path("out.ply");
  if (cli.rfind("mesh", 0) == 0) return " -o " + temp_path("out.ply");
  return " -o " + temp_path("out.png");
}

void expect_refused_by_cli(const std::string& args, const std::string& why) {
  const auto r = test::run_command(std::string(ZEROSET_BINARY) + " " + args + output_for(args));
  EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
  EXPECT_NE(r.output.find(why), std::string::npos) << args << ": " << r.output;
}

TEST(SettingsEntryPoints, EachBadValueIsRefusedWithTheSameWordsEverywhere) {
  int index = 0;
  for (const BadValue& b : kBadValues) {
    SCOPED_TRACE(b.settings);
    const std::string scene = write_scene_file(b.settings, index++);
    // The command line: the flag, and the scene file.
    if (*b.cli) expect_refused_by_cli(b.cli, b.why);
    const std::string cli = b.cli;
    const std::string subcommand = *b.cli ? cli.substr(0, cli.find(' ')) : std::string("render");
    if (std::string(b.pointer).rfind("/viewer", 0) != 0) {
      const std::string scene_args = subcommand + " " + scene;
      const auto r = test::run_command(std::string(ZEROSET_BINARY) + " " + scene_args +
                                       output_for(scene_args));
      EXPECT_EQ(r.exit_code, 2) << r.output;
      EXPECT_NE(r.output.find(std::string(b.pointer) + ": " + b.why), std::string::npos)
          << r.output;
    }
    // The viewer: the scene file (unless it is the "render" object, which the viewer does not
    // read), and the command.
    ViewerState state(sphere_scene(), Mode::kRaytrace, 1);
    if (std::string(b.pointer).rfind("/render", 0) != 0) {
      EXPECT_FALSE(state.command("load " + scene));
      EXPECT_NE(state.status().text.find(std::string(b.pointer) + ": " + b.why), std::string::npos)
          << state.status().text;
    }
    if (*b.command) {
      EXPECT_FALSE(state.command(b.command)) << b.command;
      EXPECT_NE(state.status().text.find(b.why), std::string::npos)
          << b.command << ": " << state.status().text;
    }
  }
}

TEST(SettingsEntryPoints, TheFloatersDynamicsConstantsAreRefusedAlikeBySampleAndTheViewer) {
  // Through the scene file as `zeroset sample` and the viewer read it, and through `set` (the
  // flags --feedback, --equilibrium-speed and --estimator-interval are tested with the CLI).
  struct Case {
    const char* settings;
    const char* pointer;
    const char* command;
    const char* why;
  };
  const Case cases[] = {
      {R"({"floaters": {"feedback": -1}})", "/floaters/feedback", "set floaters.feedback -1",
       "must lie in [0, 66.6667)"},
      {R"({"floaters": {"equilibrium_speed": 2000}})", "/floaters/equilibrium_speed",
       "floaters equilibrium_speed=2000", "must lie in (0, 16.6667]"},
      {R"({"floaters": {"estimator_interval": 0}})", "/floaters/estimator_interval",
       "set floaters.estimator_interval 0", "must lie in [1, 1000]"},
  };
  int index = 200;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.settings);
    const std::string scene = write_scene_file(c.settings, index++);
    const auto r =
        test::run_command(std::string(ZEROSET_BINARY) + " sample " + scene + output_for("sample"));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(std::string(c.pointer) + ": " + c.why), std::string::npos) << r.output;
    ViewerState state(sphere_scene(), Mode::kRaytrace, 1);
    EXPECT_FALSE(state.command("load " + scene));
    EXPECT_NE(state.status().text.find(std::string(c.pointer) + ": " + c.why), std::string::npos)
        << state.status().text;
    EXPECT_FALSE(state.command(c.command));
    EXPECT_NE(state.status().text.find(std::string(c.pointer) + ": " + c.why), std::string::npos)
        << state.status().text;
  }
}

TEST(SettingsEntryPoints, TheViewersLiveLimitsAreItsOwnAndSaySo) {
  // The library takes these; the viewer, which computes live, refuses them with its own words
  // for commands and scene files alike.
  FloaterOptions many;
  many.max_count = kMaxLiveFloaters + 1;
  EXPECT_NO_THROW(validate_settings(many));
  MeshSettings fine;
  fine.cells = kMaxLiveCells + 1;
  EXPECT_NO_THROW(validate_settings(fine));
  struct Case {
    const char* settings;
    const char* pointer;
    const char* command;
    const char* why;
  };
  const Case cases[] = {
      {R"({"floaters": {"max_count": 2000001}})", "/floaters/max_count",
       "floaters max_count=2000001", "the viewer simulates at most 2000000 floaters live"},
      {R"({"mesh": {"cells": 513}})", "/mesh/cells", "mesh cells=513",
       "the viewer meshes live with 4 to 512 cells"},
      {R"({"mesh": {"cells": 2}})", "/mesh/cells", "mesh cells=2",
       "the viewer meshes live with 4 to 512 cells"},
  };
  int index = 100;
  for (const Case& c : cases) {
    ViewerState state(sphere_scene(), Mode::kRaytrace, 1);
    EXPECT_FALSE(state.command("load " + write_scene_file(c.settings, index++)));
    EXPECT_NE(state.status().text.find(std::string(c.pointer) + ": " + c.why), std::string::npos)
        << state.status().text;
    EXPECT_FALSE(state.command(c.command));
    EXPECT_NE(state.status().text.find(c.why), std::string::npos) << state.status().text;
  }
}

TEST(SettingsEntryPoints, TheViewerReadsTheMeshObjectAsTheCommandLineDoes) {
  // improve as a number of steps and the boundary, which the viewer used to refuse or ignore.
  Scene scene = sphere_scene();
  scene.settings =
      nlohmann::json::parse(R"({"mesh": {"cells": 40, "improve": 25, "boundary": "fix"}})");
  ViewerState state(scene, Mode::kRaytrace, 1);
  EXPECT_EQ(state.mesh_settings().cells, 40);
  EXPECT_TRUE(state.mesh_settings().improve);
  EXPECT_EQ(state.mesh_settings().max_improve_steps, 25);
  EXPECT_EQ(state.mesh_settings().boundary, BoundaryMode::kFixed);
  // Written back as read, with every other key at its default.
  for (const auto& [key, value] : scene.settings["mesh"].items())
    EXPECT_EQ(state.scene().settings["mesh"][key], value) << key;
  EXPECT_EQ(state.scene().settings["mesh"].size(), mesh_settings_to_json(MeshSettings{}).size());
  Scene unknown = sphere_scene();
  unknown.settings = nlohmann::json::parse(R"({"mesh": {"cels": 40}})");
  EXPECT_THROW(ViewerState(unknown, Mode::kRaytrace, 1), BadInput);
}

}  // namespace
}  // namespace zeroset::viewer
