// Scripts drive the viewer like a user: commands in order, frames in between, failures
// counted unless expected.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "script.h"
#include "viewer_state.h"
#include "zeroset/error.h"
#include "zeroset/surface/catalog.h"

namespace zeroset::viewer {
namespace {

class FakeHost : public ScriptHost {
 public:
  void save_screenshot(const std::string& path) override {
    if (path.find("/nonexistent/") != std::string::npos) throw IoError(path, "no such directory");
    screenshots.push_back(path);
  }
  void set_ui_visible(bool visible) override { ui = visible; }
  void print(const std::string& line) override { log += line + "\n"; }

  std::vector<std::string> screenshots;
  bool ui = true;
  std::string log;
};

Scene kummer() { return Scene{make_surface(*find_catalog_entry("kummer")), {}}; }

// Advances the script one "frame" at a time (1/60 s apart); returns the frames it took.
int run(Script& script, ViewerState& state, FakeHost& host, int max_frames = 10000) {
  double t = 0;
  int frames = 0;
  while (!script.is_finished() && frames < max_frames) {
    state.update(t);
    script.advance(state, host, t);
    t += 1.0 / 60;
    ++frames;
  }
  return frames;
}

TEST(Script, ParseRejectsABadLineBeforeAnythingRuns) {
  try {
    Script::parse("mode mesh\n\n# fine\nframes ten\n", "demo.txt");
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("demo.txt:4"), std::string::npos) << e.what();
  }
  EXPECT_THROW(Script::parse("mode sideways\n", "s"), InvalidArgument);
  EXPECT_THROW(Script::parse("teleport\n", "s"), InvalidArgument);
  EXPECT_THROW(Script::load("/nonexistent/script.txt"), IoError);
}

TEST(Script, RunsCommandsInOrderWithFramesBetween) {
  Script script = Script::parse(
      "param mu 2\nframes 5\nui off\nscreenshot a.png\ncamera 10 10\nsleep 0.5\nstats\n", "s");
  ViewerState state(kummer(), Mode::kRaytrace);
  FakeHost host;
  const int frames = run(script, state, host);
  EXPECT_EQ(script.failures(), 0) << host.log;
  EXPECT_EQ(state.surface().field.parameter_values()[0], 2.0);
  EXPECT_EQ(state.camera().azimuth_deg, 10);
  EXPECT_FALSE(host.ui);
  EXPECT_EQ(host.screenshots, std::vector<std::string>{"a.png"});
  EXPECT_GE(frames, 5 + 1 + 30);  // frames, the frame after `ui off`, half a second
  EXPECT_NE(host.log.find("\"mode\":\"raytrace\""), std::string::npos) << host.log;
}

TEST(Script, ExpectErrorAcceptsAFailureAndUnexpectedOnesAreCounted) {
  Script script = Script::parse(
      "equation x^2 +\n"
      "expect-error expected an operand\n"
      "param nu 1\n"
      "equation x^2 + y^2 - z^2\n"
      "expect-error\n"
      "screenshot /nonexistent/a.png\n",
      "s");
  ViewerState state(kummer(), Mode::kRaytrace);
  FakeHost host;
  run(script, state, host);
  // `param nu` failed unexpectedly, the good equation did not fail although expected to,
  // and the screenshot could not be written.
  EXPECT_EQ(script.failures(), 3) << host.log;
  EXPECT_NE(host.log.find("failed as expected"), std::string::npos) << host.log;
  EXPECT_EQ(state.surface().field.source(), "x^2 + y^2 - z^2");
}

TEST(Script, ProjectionSwitchesTheCameraAndRefusesBadHeights) {
  Script script = Script::parse(
      "projection orthographic 3.5\nframes 2\nprojection ortho\n"
      "projection perspective 2\nexpect-error only an orthographic camera\n"
      "projection orthographic -1\nexpect-error must be positive\n"
      "projection fisheye\nexpect-error expected perspective or orthographic\n",
      "s");
  ViewerState state(kummer(), Mode::kRaytrace);
  FakeHost host;
  run(script, state, host);
  EXPECT_EQ(script.failures(), 0) << host.log;
  EXPECT_TRUE(state.camera().is_orthographic());
  EXPECT_EQ(state.camera().ortho_height, 3.5);  // "projection ortho" keeps the height
  Script back = Script::parse("projection perspective\n", "s");
  run(back, state, host);
  EXPECT_FALSE(state.camera().is_orthographic());
}

TEST(Script, WaitTimesOutAsAFailure) {
  // Floaters never settle while the parameter keeps moving.
  Script script = Script::parse("play mu\nwait 0.2\n", "s");
  ViewerState state(kummer(), Mode::kFloaters);
  FakeHost host;
  run(script, state, host);
  EXPECT_EQ(script.failures(), 1) << host.log;
  EXPECT_NE(host.log.find("did not settle"), std::string::npos);
}

TEST(Script, StepsNeedsFloatersMode) {
  Script script = Script::parse("steps 10\n", "s");
  ViewerState state(kummer(), Mode::kRaytrace);
  FakeHost host;
  run(script, state, host);
  EXPECT_EQ(script.failures(), 1);
}

TEST(Script, QuitEndsTheScriptEarly) {
  Script script = Script::parse("quit\nparam mu 2\n", "s");
  ViewerState state(kummer(), Mode::kRaytrace);
  FakeHost host;
  run(script, state, host);
  EXPECT_TRUE(script.is_finished());
  EXPECT_EQ(state.surface().field.parameter_values()[0], 1.5);
}

}  // namespace
}  // namespace zeroset::viewer
