// The viewer against hostile scenes: a clip of a million parts is refused at once, a clip at
// the limit does not keep the viewer from closing (its jobs are cancelled at a coarse grain).
// Runs the `zeroset` binary in a virtual X server (xvfb-run) with Mesa's software OpenGL.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "support/run_command.h"
#include "support/temp_path.h"
#include "support/xvfb.h"
#include "zeroset/surface/clip.h"

namespace zeroset {
namespace {

using test::run_command;

using test::has_xvfb;

using zeroset::test::temp_path;

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = temp_path(name);
  std::ofstream(path) << text;
  return path;
}

// A scene of the Kummer surface whose clip lists `parts` balls (all reaching past the scene).
std::string clip_scene(const std::string& name, std::size_t parts) {
  std::string clips;
  clips.reserve(parts * 16);
  for (std::size_t k = 0; k < parts; ++k)
    clips += (k ? ",\"sphere:" : "\"sphere:") + std::to_string(3 + k % 1000) + "\"";
  return write_file(name,
                    "{\"zeroset_scene\": 1, \"name\": \"kummer\", \"clip\": [" + clips + "]}");
}

struct Timed {
  test::CommandResult result;
  double seconds = 0;
};

Timed view(const std::string& args) {
  const auto t0 = std::chrono::steady_clock::now();
  Timed t;
  t.result = test::run_viewer(ZEROSET_BINARY, args, "1024x768");
  t.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return t;
}

TEST(ViewerFaults, AMillionClipsOnTheCommandLineAreRefusedBeforeTheWindow) {
  const std::string scene = clip_scene("million.json", 1'000'000);
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = run_command(std::string(ZEROSET_BINARY) + " view " + scene + " --frames 1");
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/clip/" + std::to_string(kMaxClipParts)), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("at most 256 parts"), std::string::npos) << r.output;
  EXPECT_LT(s, 10) << r.output;
}

// A script that never ends (a device such as /dev/zero) or is too long is refused before the
// window opens, without reading more than the limit.
TEST(ViewerFaults, AnEndlessScriptIsRefusedBeforeTheWindow) {
  for (const std::string script : {"/dev/zero", "/dev/urandom"}) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto r = run_command(std::string(ZEROSET_BINARY) + " view kummer --frames 1 --script " +
                               script);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(script + ": larger than a viewer script may be (16 MiB)"),
              std::string::npos)
        << r.output;
    EXPECT_LT(s, 10) << r.output;
  }
}

// The keyframe panel (open for a scene with keyframes) draws only the rows in view: each of
// 50,000 rows asked for the frame count, a pass over every keyframe, and a frame took seconds
// (3.3 s at 20,000 keyframes).
TEST(ViewerFaults, FiftyThousandKeyframesDoNotSlowTheFrames) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  constexpr int kKeyframes = 50'000;
  std::string keys;
  keys.reserve(kKeyframes * 48);
  for (int k = 0; k < kKeyframes; ++k)
    keys += (k ? ",{\"time\": " : "{\"time\": ") + std::to_string(k / (kKeyframes - 1.0)) +
            ", \"params\": {\"a\": " + std::to_string(1 + 1e-5 * k) + "}}";
  const std::string scene = write_file(
      "keyframes.json", R"({"equation": "x^2 + y^2 + z^2 - a", "parameters": {"a": 1},
        "clip": ["sphere:2"], "animation": {"keyframes": [)" + keys + "]}}");
  const Timed t = view(scene + " --size 640x480 --frames 30");
  EXPECT_EQ(t.result.exit_code, 0) << t.result.output;
  EXPECT_LT(t.seconds, 40) << t.result.output;
}

TEST(ViewerFaults, LoadingAMillionClipsThenQuitIsPrompt) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  const std::string scene = clip_scene("million-load.json", 1'000'000);
  const std::string script =
      write_file("load-million.txt", "frames 2\nload " + scene + "\nexpect-error at most\nquit\n");
  const Timed t = view("kummer --size 400x300 --script " + script);
  EXPECT_EQ(t.result.exit_code, 0) << t.result.output;
  EXPECT_NE(t.result.output.find("failed as expected"), std::string::npos) << t.result.output;
  // Minutes before the clip limit and the cancellable set-up; the rest is the X server.
  EXPECT_LT(t.seconds, 20) << t.result.output;
}

// At the clip limit in floaters mode, where the set-up tests every part at every point: the
// viewer still closes at once when the script ends.
TEST(ViewerFaults, AClipAtTheLimitDoesNotHoldTheExit) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  const std::string scene = clip_scene("at-limit.json", kMaxClipParts);
  for (const char* mode : {"floaters", "mesh", "raytrace"}) {
    const std::string script =
        write_file(std::string("at-limit-") + mode + ".txt",
                   std::string("mode ") + mode + "\nsingular on\nframes 3\nquit\n");
    const Timed t = view(scene + " --size 400x300 --script " + script);
    EXPECT_EQ(t.result.exit_code, 0) << mode << "\n" << t.result.output;
    EXPECT_LT(t.seconds, 20) << mode << "\n" << t.result.output;
  }
}

// ImGui's slider aborts for bounds beyond ±DBL_MAX/2: the panel clamps every range it draws. A
// scene with the range ±1e308 (should a reader let it through) is drawn, not an abort.
TEST(ViewerFaults, ExtremeParameterRangesDoNotAbortTheSlider) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed";
  const std::string scene =
      write_file("huge-range.json",
                 "{\"zeroset_scene\": 1, \"equation\": \"a*x^2 + y^2 + z^2 - 1\", \"clip\": "
                 "[\"sphere:2\"], \"parameters\": {\"a\": {\"value\": 1, \"min\": -1e308, "
                 "\"max\": 1e308}}}");
  const std::string script = write_file(
      "huge-range.txt", "load " + scene + "\nframes 3\nrange a -1e300 1e300\nframes 3\nquit\n");
  const Timed t = view("sphere --size 640x480 --script " + script);
  // 1: a command refused (the range beyond the parameter limit), as it must be.
  EXPECT_TRUE(t.result.exit_code == 0 || t.result.exit_code == 1) << t.result.output;
  EXPECT_EQ(t.result.output.find("Assertion"), std::string::npos) << t.result.output;
  EXPECT_NE(t.result.output.find(":5: quit"), std::string::npos) << t.result.output;
}

}  // namespace
}  // namespace zeroset
