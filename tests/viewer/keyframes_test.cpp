// The viewer's keyframes: loaded from a scene and saved back unchanged, played and scrubbed
// through the tracks `zeroset animate` reads (read_keyframes), recorded by commands, and bad
// keyframe commands refused with a message that leaves the keyframes as they were.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "support/file_bytes.h"
#include "support/temp_path.h"
#include "viewer_state.h"
#include "zeroset/error.h"
#include "zeroset/surface/keyframes.h"
#include "zeroset/surface/scene.h"

namespace zeroset::viewer {
namespace {

using json = nlohmann::json;
using test::file_bytes;

using zeroset::test::temp_path;

// A torus whose radii and camera move through three keyframes with three eases, one of them
// placed by frame.
const char* kTorus = R"j({"equation": "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
  "parameters": {"R": 0.75, "r": 0.25}, "clip": ["sphere:2"],
  "camera": {"azimuth_deg": 30, "elevation_deg": 20},
  "animation": {"keyframes": [
    {"time": 0, "params": {"R": 0.75, "r": 0.25},
     "camera": {"azimuth_deg": 0, "elevation_deg": 10, "distance": 7}},
    {"frame": 20, "params": {"r": 0.5}, "camera": {"elevation_deg": 60, "roll_deg": 0},
     "ease": "in"},
    {"time": 1, "params": {"R": 1.25, "r": 0.4},
     "camera": {"azimuth_deg": 120, "distance": 5, "roll_deg": 30}, "ease": "linear"}]}})j";

std::string write_torus(const std::string& name) {
  const std::string path = temp_path(name);
  std::ofstream(path) << kTorus;
  return path;
}

double param(const ViewerState& s, const std::string& name) {
  const Field& f = s.surface().field;
  return f.parameter_values()[f.parameter_index(name)];
}

// The state shows what read_keyframes' tracks give at `time` (60 frames place frame 20).
void expect_shows(const ViewerState& s, const Scene& scene, double time) {
  const Keyframes keys = read_keyframes(scene.settings, scene.surface, 60, "torus");
  const Surface at = keys.at(scene.surface, time);
  for (const char* p : {"R", "r"})
    EXPECT_DOUBLE_EQ(param(s, p), at.field.parameter_values()[at.field.parameter_index(p)])
        << p << " at " << time;
  EXPECT_DOUBLE_EQ(s.camera().azimuth_deg, at.camera.azimuth_deg) << time;
  EXPECT_DOUBLE_EQ(s.camera().elevation_deg, at.camera.elevation_deg) << time;
  EXPECT_DOUBLE_EQ(s.camera().distance, at.camera.distance) << time;
  EXPECT_DOUBLE_EQ(s.camera().roll_deg, at.camera.roll_deg) << time;
}

TEST(ViewerKeyframes, ScrubbingAndPlayingFollowTheTracksOfZerosetAnimate) {
  const Scene scene = read_scene(write_torus("play.json"));
  ViewerState s(scene, Mode::kRaytrace, 1, "torus.json");
  ASSERT_EQ(s.keyframes().size(), 3u);
  EXPECT_DOUBLE_EQ(s.keyframe_time(1), 20.0 / 59);
  EXPECT_EQ(s.keyframe_ease(0), Ease::kInOut);
  EXPECT_EQ(s.keyframe_ease(1), Ease::kIn);
  for (const double t : {0.0, 0.1, 20.0 / 59, 0.5, 0.77, 1.0}) {
    ASSERT_TRUE(s.scrub_keyframes(t)) << s.status().text;
    expect_shows(s, scene, t);
  }
  ASSERT_TRUE(s.command("keyframe time 0.25")) << s.status().text;
  expect_shows(s, scene, 0.25);
  EXPECT_EQ(s.keyframe_playhead(), 0.25);

  // Playing: the time runs at `speed` animations per second, back and forth with loop; every
  // frame shows the tracks at the playhead.
  ASSERT_TRUE(s.command("keyframe time 0"));
  ASSERT_TRUE(s.set_speed(0.5));
  EXPECT_FALSE(s.play("R")) << "one parameter alone is not what the keyframes animate";
  EXPECT_NE(s.status().text.find("keyframe clear"), std::string::npos) << s.status().text;
  ASSERT_TRUE(s.play()) << s.status().text;
  double lo = 1, hi = 0;
  int turns = 0, direction = s.animation().direction;
  for (int i = 1; i <= 300; ++i) {  // 6 s at 50 frames per second: three sweeps
    s.update(0.02 * i);
    const double t = s.keyframe_playhead();
    lo = std::min(lo, t);
    hi = std::max(hi, t);
    turns += s.animation().direction != direction;
    direction = s.animation().direction;
    if (i % 37 == 0) expect_shows(s, scene, t);
  }
  EXPECT_GE(lo, 0.0);
  EXPECT_LE(hi, 1.0);
  EXPECT_GT(hi, 0.95);
  EXPECT_LT(lo, 0.05);
  EXPECT_GE(turns, 2);
  EXPECT_TRUE(s.animation().is_playing);

  // Without loop it stops at the end, showing the last keyframe.
  s.set_loop(false);
  ASSERT_TRUE(s.command("keyframe time 0.9"));
  ASSERT_TRUE(s.play());
  if (s.animation().direction < 0) {
    ASSERT_TRUE(s.play());  // heading for 1
  }
  for (int i = 1; i <= 200 && s.animation().is_playing; ++i) s.update(10 + 0.02 * i);
  EXPECT_FALSE(s.animation().is_playing);
  expect_shows(s, scene, s.keyframe_playhead());
  EXPECT_TRUE(s.keyframe_playhead() == 0.0 || s.keyframe_playhead() == 1.0);
}

TEST(ViewerKeyframes, KeyframesByFrameBeyondTheDefaultCountAreKeptInTheirPlace) {
  Scene scene = read_scene(write_torus("frames.json"));
  scene.settings["animation"]["keyframes"][2] = json::parse(R"({"frame": 99, "params": {"R": 1}})");
  scene.settings["animation"]["keyframes"][1]["frame"] = 33.0;  // whole, written as a float
  ViewerState s(scene, Mode::kRaytrace, 1);
  EXPECT_EQ(s.keyframe_frames(), 100);
  EXPECT_DOUBLE_EQ(s.keyframe_time(1), 1.0 / 3);
  EXPECT_DOUBLE_EQ(s.keyframe_time(2), 1.0);
  ASSERT_TRUE(s.add_keyframe(0.5)) << s.status().text;
  EXPECT_EQ(s.keyframes()[1]["frame"], 33.0);
  EXPECT_EQ(s.keyframes()[2]["time"], 0.5);
}

TEST(ViewerKeyframes, SavingWritesTheLoadedKeyframesBackAsTheyCame) {
  const std::string original = write_torus("original.json");
  ViewerState s(read_scene(original), std::nullopt, 1, original);
  const std::string once = temp_path("once.json"), twice = temp_path("twice.json");
  ASSERT_TRUE(s.save_scene(once)) << s.status().text;
  const json a = json::parse(file_bytes(original)), b = json::parse(file_bytes(once));
  EXPECT_EQ(b["animation"]["keyframes"], a["animation"]["keyframes"]);
  ASSERT_TRUE(s.load_scene(once)) << s.status().text;
  ASSERT_TRUE(s.save_scene(twice)) << s.status().text;
  EXPECT_EQ(file_bytes(twice), file_bytes(once)) << "a second save is byte for byte the first";
  // No keyframes: none written.
  s.clear_keyframes();
  ASSERT_TRUE(s.save_scene(twice));
  EXPECT_FALSE(json::parse(file_bytes(twice))["animation"].contains("keyframes"));
}

TEST(ViewerKeyframes, CommandsRecordTheCurrentParametersAndCamera) {
  ViewerState s(read_scene(write_torus("record.json")), Mode::kRaytrace, 1);
  s.clear_keyframes();
  for (const char* line :
       {"param R 0.8", "param r 0.3", "camera 10 20 6", "keyframe add 0 in", "param R 1.2",
        "camera 100 40 5", "keyframe add 1 linear", "param r 0.45", "camera 50 30 5.5",
        "keyframe add 0.5", "keyframe ease 1 out", "keyframe move 1 0.4"})
    ASSERT_TRUE(s.command(line)) << line << ": " << s.status().text;
  const json& k = s.keyframes();
  ASSERT_EQ(k.size(), 3u);
  EXPECT_EQ(k[0]["time"], 0.0);
  EXPECT_EQ(k[0]["ease"], "in");
  EXPECT_EQ(k[0]["params"], (json{{"R", 0.8}, {"r", 0.3}}));
  EXPECT_EQ(k[0]["camera"]["azimuth_deg"], 10.0);
  EXPECT_EQ(k[0]["camera"]["distance"], 6.0);
  EXPECT_EQ(k[1]["time"], 0.4);
  EXPECT_EQ(k[1]["ease"], "out");
  EXPECT_EQ(k[1]["params"], (json{{"R", 1.2}, {"r", 0.45}}));
  EXPECT_EQ(k[2]["time"], 1.0);
  EXPECT_EQ(k[2]["camera"]["elevation_deg"], 40.0);
  // update records the state now into a keyframe, keeping its time.
  ASSERT_TRUE(s.command("param R 0.9"));
  ASSERT_TRUE(s.command("keyframe update 0"));
  EXPECT_EQ(s.keyframes()[0]["params"]["R"], 0.9);
  EXPECT_EQ(s.keyframes()[0]["time"], 0.0);
  EXPECT_EQ(s.keyframes()[0]["ease"], "in");
  ASSERT_TRUE(s.command("keyframe delete 1"));
  EXPECT_EQ(s.keyframes().size(), 2u);
  // What was recorded reads as a scene file's keyframes.
  const std::string saved = temp_path("recorded.json");
  ASSERT_TRUE(s.save_scene(saved)) << s.status().text;
  const Scene back = read_scene(saved);
  const Keyframes tracks = read_keyframes(back.settings, back.surface, 60, saved);
  ASSERT_NE(tracks.param("R"), nullptr);
  EXPECT_EQ(tracks.param("R")->values, (std::vector<double>{0.9, 1.2}));
  EXPECT_EQ(tracks.camera.size(), 5u);
}

TEST(ViewerKeyframes, BadKeyframeCommandsAreRefusedAndChangeNothing) {
  ViewerState s(read_scene(write_torus("bad.json")), Mode::kRaytrace, 1);
  const json before = s.keyframes();
  const std::pair<const char*, const char*> bad[] = {
      {"keyframe add 1.5", "must lie in [0, 1]"},
      {"keyframe add -0.1", "must lie in [0, 1]"},
      {"keyframe add nan", "keyframe time"},
      {"keyframe add 0", "keyframe 0 is at time 0 already"},
      {"keyframe add 0.5 bouncy", "expected linear, in, out or in-out"},
      {"keyframe ease 0 bouncy", "expected linear, in, out or in-out"},
      {"keyframe move 1 0", "keyframes must stay in increasing time"},
      {"keyframe move 1 1", "keyframes must stay in increasing time"},
      {"keyframe move 0 0.9", "keyframes must stay in increasing time"},
      {"keyframe delete 3", "expected 0 to 2"},
      {"keyframe delete -1", "keyframe index"},
      {"keyframe update 99", "expected 0 to 2"},
      {"keyframe ease 5 in", "expected 0 to 2"},
      {"keyframe delete", "usage: keyframe delete INDEX"},
      {"keyframe time 2", "must lie in [0, 1]"},
      {"keyframe frobnicate", "expected add, update, ease, move, delete, clear or time"},
      {"keyframe", "usage"},
  };
  for (const auto& [line, why] : bad) {
    EXPECT_FALSE(s.command(line)) << line;
    EXPECT_TRUE(s.status().is_error) << line;
    EXPECT_NE(s.status().text.find(why), std::string::npos) << line << ": " << s.status().text;
    EXPECT_EQ(s.keyframes(), before) << line;
  }
  // Without keyframes, indices and scrubbing say there are none.
  s.clear_keyframes();
  EXPECT_FALSE(s.command("keyframe delete 0"));
  EXPECT_NE(s.status().text.find("there are no keyframes"), std::string::npos);
  EXPECT_FALSE(s.command("keyframe time 0.5"));
  EXPECT_TRUE(s.play()) << "without keyframes play animates a parameter again";
}

TEST(ViewerKeyframes, KeyframesTheSurfaceNoLongerFitsAreNamedNotSaved) {
  ViewerState s(read_scene(write_torus("lost.json")), Mode::kRaytrace, 1);
  ASSERT_TRUE(s.set_equation("x^2 + y^2 + z^2 - R^2"));  // r is gone
  EXPECT_FALSE(s.play());
  EXPECT_NE(s.status().text.find("/animation/keyframes/0/params/r"), std::string::npos)
      << s.status().text;
  const std::string path = temp_path("lost-saved.json");
  std::filesystem::remove(path);
  EXPECT_FALSE(s.save_scene(path));
  EXPECT_NE(s.status().text.find("the surface has no parameter 'r'"), std::string::npos)
      << s.status().text;
  EXPECT_FALSE(std::filesystem::exists(path));
  s.clear_keyframes();
  EXPECT_TRUE(s.save_scene(path)) << s.status().text;
}

TEST(ViewerKeyframes, MalformedKeyframesInASceneAreBadInputNamingTheEntry) {
  Scene scene = read_scene(write_torus("malformed.json"));
  scene.settings["animation"]["keyframes"][1]["ease"] = "bouncy";
  try {
    ViewerState s(scene, std::nullopt, 1, "saved.json");
    FAIL() << "expected BadInput";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("saved.json: /animation/keyframes/1/ease"),
              std::string::npos)
        << e.what();
  }
  // Loading it into a running viewer fails and keeps what is shown.
  ViewerState s(read_scene(write_torus("good.json")), Mode::kRaytrace, 1);
  std::string text = kTorus;
  text.replace(text.find("\"ease\": \"in\""), 12, "\"ease\": \"bouncy\"");
  const std::string path = temp_path("malformed-file.json");
  std::ofstream(path) << text;
  EXPECT_FALSE(s.load_scene(path));
  EXPECT_NE(s.status().text.find("/animation/keyframes/1/ease"), std::string::npos)
      << s.status().text;
  EXPECT_EQ(s.keyframes().size(), 3u);
}

}  // namespace
}  // namespace zeroset::viewer
