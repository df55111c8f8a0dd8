// `zeroset animate` and `zeroset export` as a user (or a batch scheduler) runs them: the frames
// and their names, parts of an animation, refused input, and scenes POV-Ray reads.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "cli/cli_support.h"
#include "render/image_masks.h"
#include "zeroset/io/image.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;
using test::fresh_dir;
using test::run_command;
using test::zs;

std::set<std::string> files_in(const std::string& dir) {
  std::set<std::string> names;
  if (!fs::is_directory(dir)) return names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

std::string bytes_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

bool have_povray() { return run_command("command -v povray").exit_code == 0; }

// A torus whose tube grows, seen from a camera that turns: every frame differs.
const std::string kTorus =
    "animate torus --param r=0.2:0.9 --orbit 40 --size 40x32 --aa 1 --no-video";

TEST(CliAnimate, WritesEveryFrameNumberedFromZero) {
  const std::string dir = fresh_dir("animate-all") + "/frames";  // made by the command
  const auto r = run_command(zs(kTorus + " --frames 4 -o " + dir));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(files_in(dir), (std::set<std::string>{"frame_0000.png", "frame_0001.png",
                                                  "frame_0002.png", "frame_0003.png"}));
  std::vector<std::string> frames;
  for (int f = 0; f < 4; ++f) {
    const Image img = read_image(dir + "/frame_000" + std::to_string(f) + ".png");
    EXPECT_EQ(img.width, 40);
    EXPECT_EQ(img.height, 32);
    frames.push_back(bytes_of(dir + "/frame_000" + std::to_string(f) + ".png"));
  }
  for (int f = 1; f < 4; ++f) EXPECT_NE(frames[f], frames[f - 1]) << "frame " << f;
  EXPECT_NE(r.output.find("wrote 4 frames"), std::string::npos) << r.output;
}

TEST(CliAnimate, AFrameRangeWritesExactlyThoseFramesAsTheFullRunDoes) {
  const std::string root = fresh_dir("animate-range");
  const std::string full = root + "/full", part = root + "/part";
  auto r = run_command(zs(kTorus + " --frames 10 -o " + full));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_command(zs(kTorus + " --frames 10 --frame-range 3-5 -o " + part));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(files_in(part),
            (std::set<std::string>{"frame_0003.png", "frame_0004.png", "frame_0005.png"}));
  EXPECT_EQ(files_in(full).size(), 10u);
  for (const char* name : {"frame_0003.png", "frame_0004.png", "frame_0005.png"}) {
    const std::string a = bytes_of(full + "/" + name), b = bytes_of(part + "/" + name);
    EXPECT_FALSE(a.empty()) << name;
    EXPECT_TRUE(a == b) << name << " differs from the full run's";
  }
  // A second part into the same directory adds its frames beside the first's.
  r = run_command(zs(kTorus + " --frames 10 --frame-range 9 -o " + part));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(files_in(part).size(), 4u);
  EXPECT_TRUE(bytes_of(full + "/frame_0009.png") == bytes_of(part + "/frame_0009.png"));
}

TEST(CliAnimate, BadFrameRangesExitTwoAndWriteNothing) {
  const std::string root = fresh_dir("animate-bad");
  for (const char* range :
       {"5-3", "3-10", "10-10", "a-b", "-1-3", "3--5", "1.5-2", "3-", "-", "''", "1e1-2"}) {
    const std::string dir = root + "/frames";
    const auto r = run_command(zs(kTorus + " --frames 10 --frame-range " + range + " -o " + dir));
    EXPECT_EQ(r.exit_code, 2) << range << ": " << r.output;
    EXPECT_NE(r.output.find("--frame-range"), std::string::npos) << range << ": " << r.output;
    EXPECT_FALSE(fs::exists(dir)) << range;
  }
  // Into an existing directory: it stays empty.
  const std::string dir = fresh_dir("animate-bad-existing");
  auto r = run_command(zs(kTorus + " --frames 10 --frame-range 8-12 -o " + dir));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_TRUE(files_in(dir).empty());
  // Frames, too, are checked; and a part of the animation makes no video.
  r = run_command(zs(kTorus + " --frames 0 -o " + dir));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r =
      run_command(zs("animate torus --param r=0.2:0.9 --size 40x32 --frames 10 --frame-range 2-4 "
                     "--video " +
                     dir + "/part.mp4 -o " + dir));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--video"), std::string::npos) << r.output;
  EXPECT_TRUE(files_in(dir).empty());
}

/// A fake ffmpeg first on PATH in `root`/bin: `script` is its body.
std::string with_fake_ffmpeg(const std::string& root, const std::string& script) {
  const std::string bin = root + "/bin";
  fs::create_directories(bin);
  std::ofstream(bin + "/ffmpeg") << "#!/bin/sh\n" << script;
  fs::permissions(bin + "/ffmpeg", fs::perms::owner_all);
  return "PATH=" + bin + ":$PATH ";
}

TEST(CliAnimate, AFailingEncoderIsAnErrorAndLeavesNoFrameAndNoVideo) {
  const std::string root = fresh_dir("animate-ffmpeg");
  const std::string path = with_fake_ffmpeg(root, "echo 'encoder says no' >&2\nexit 1\n");
  const auto r = run_command(path + zs("animate torus --param r=0.2:0.9 --size 32x32 --frames 2 "
                                       "-o " +
                                       root + "/frames"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("encoder says no"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--no-video"), std::string::npos) << r.output;
  // One transaction: the directory the command made is gone again, and no temp file is left.
  EXPECT_FALSE(fs::exists(root + "/frames")) << r.output;
  EXPECT_EQ(files_in(root), (std::set<std::string>{"bin"}));
}

TEST(CliAnimate, TheEncoderReadsTheFramesBeforeTheyAreMovedIntoPlace) {
  // The fake ffmpeg checks that frame 0 of its -i pattern exists and writes the video's name.
  const std::string root = fresh_dir("animate-ffmpeg-ok");
  const std::string path = with_fake_ffmpeg(root, R"(
while [ $# -gt 1 ]; do
  if [ "$1" = "-i" ]; then first=$(printf "$2" 0); fi
  shift
done
[ -f "$first" ] || { echo "no frame $first" >&2; exit 1; }
echo video > "$1"
)");
  const auto r = run_command(path + zs("animate torus --param r=0.2:0.9 --size 32x32 --frames 3 "
                                       "-o " +
                                       root + "/frames"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(files_in(root + "/frames"),
            (std::set<std::string>{"animation.mp4", "frame_0000.png", "frame_0001.png",
                                   "frame_0002.png"}));
  EXPECT_EQ(bytes_of(root + "/frames/animation.mp4"), "video\n");
}

TEST(CliExport, WritesAPovSceneThatPovRayRenders) {
  const std::string dir = fresh_dir("export-pov");
  const std::string pov = dir + "/kummer.pov", png = dir + "/kummer.png";
  auto r = run_command(zs("export kummer --param mu=2 --camera 40,25 --size 32x32 -o " + pov));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string text = bytes_of(pov);
  EXPECT_NE(text.find("polynomial { 4,"), std::string::npos);
  EXPECT_NE(r.output.find("povray +W32 +H32"), std::string::npos) << r.output;
  if (!have_povray()) GTEST_SKIP() << "povray is not installed: the scene is not rendered";
  r = run_command("povray -D -V +W32 +H32 +I" + pov + " +O" + png);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image theirs = read_image(png);
  EXPECT_EQ(theirs.width, 32);
  EXPECT_EQ(theirs.height, 32);
  // The same silhouette as zeroset's own picture.
  r = run_command(
      zs("render kummer --param mu=2 --camera 40,25 --size 32x32 --aa 1 -o " + dir + "/ours.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image ours = read_image(dir + "/ours.png");
  const Color white(1, 1, 1);
  const double iou = test::intersection_over_union(test::surface_mask(theirs, white),
                                                   test::surface_mask(ours, white));
  EXPECT_GE(iou, 0.97);
}

TEST(CliExport, RefusesWhatItCannotWriteAndWritesNothing) {
  const std::string dir = fresh_dir("export-bad");
  for (const std::string& args :
       {"export \"sqrt(x^2 + y^2) - z\" --clip sphere:1 -o " + dir + "/a.pov",
        "export \"x^2 + y^2 - z^2\" -o " + dir + "/b.pov",  // unbounded: no clip
        "export kummer -o " + dir + "/c.png", "export kummer --format obj -o " + dir + "/d.pov",
        "export kummer --size 0x10 -o " + dir + "/e.pov"}) {
    const auto r = run_command(zs(args));
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.output;
    EXPECT_NE(r.output.find("error"), std::string::npos) << args << ": " << r.output;
  }
  EXPECT_TRUE(files_in(dir).empty());
}

// ---- keyframes ------------------------------------------------------------------------------

// A torus whose radii (two parameters) and camera (azimuth, elevation, distance, roll) move
// through three keyframes with three eases; the middle one is frame 4 of 9 (time 0.5).
std::string keyframed_scene(const std::string& dir, const std::string& keyframes) {
  const std::string path = dir + "/torus.json";
  std::ofstream(path) << R"j({"equation": "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
    "parameters": {"R": 0.75, "r": 0.25}, "clip": ["sphere:2"],
    "camera": {"azimuth_deg": 30, "elevation_deg": 20},
    "animation": {"keyframes": )j" +
                             keyframes + "}}";
  return path;
}

const std::string kKeyframes = R"([
  {"time": 0, "params": {"R": 0.75, "r": 0.25},
   "camera": {"azimuth_deg": 0, "elevation_deg": 10, "distance": 7}},
  {"frame": 4, "params": {"r": 0.5}, "camera": {"elevation_deg": 60, "roll_deg": 0}, "ease": "in"},
  {"time": 1, "params": {"R": 1.25, "r": 0.4},
   "camera": {"azimuth_deg": 120, "distance": 5, "roll_deg": 30}, "ease": "linear"}])";

TEST(CliKeyframes, AnimateFollowsTheKeyframesOfTheSceneFile) {
  const std::string dir = fresh_dir("keyframes-animate");
  const std::string scene = keyframed_scene(dir, kKeyframes);
  auto r = run_command(
      zs("animate " + scene + " --frames 9 --size 48x48 --aa 1 --no-video -o " + dir + "/frames"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_EQ(files_in(dir + "/frames").size(), 9u);
  // Frame 4 is the middle keyframe: r and the elevation as it gives them, R, the azimuth and
  // the distance halfway (smoothstep and linear both give 1/2 there).
  r = run_command(zs("render " + scene +
                     " --param R=1 --param r=0.5 --camera 60,60,6,0 "
                     "--size 48x48 --aa 1 -o " +
                     dir + "/still.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(bytes_of(dir + "/still.png") == bytes_of(dir + "/frames/frame_0004.png"));
  // And the frames between keyframes are not the keyframes' pictures.
  EXPECT_FALSE(bytes_of(dir + "/frames/frame_0003.png") ==
               bytes_of(dir + "/frames/frame_0004.png"));
}

TEST(CliKeyframes, PovRayRendersTheSameFramesFromTheExportedAnimation) {
  if (!have_povray()) GTEST_SKIP() << "povray is not installed";
  const std::string dir = fresh_dir("keyframes-pov");
  const std::string scene = keyframed_scene(dir, kKeyframes);
  auto r = run_command(zs("animate " + scene +
                          " --frames 9 --frame-range 2-4 --size 48x48 "
                          "--aa 1 --no-video -o " +
                          dir + "/frames"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_command(zs("export " + scene +
                     " --animate --frames 9 --frame-range 2-4 --size 48x48 "
                     "-o " +
                     dir + "/pov/torus.pov"));
  ASSERT_NE(r.exit_code, 0) << "the directory pov/ does not exist yet";
  fs::create_directories(dir + "/pov");
  r = run_command(zs("export " + scene +
                     " --animate --frames 9 --frame-range 2-4 --size 48x48 "
                     "-o " +
                     dir + "/pov/torus.pov"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string ini = bytes_of(dir + "/pov/torus.ini");
  for (const char* line : {"Initial_Frame=0\n", "Final_Frame=8\n", "Initial_Clock=0\n",
                           "Final_Clock=1\n", "Subset_Start_Frame=2\n", "Subset_End_Frame=4\n"})
    EXPECT_NE(ini.find(line), std::string::npos) << line << " in\n" << ini;
  // Without anti-aliasing (-A after the .ini overrides it), as zeroset's --aa 1 frames: the
  // silhouettes' edges are then decided by one ray per pixel on both sides.
  r = run_command("cd " + dir + "/pov && povray -D -V torus.ini -A");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(files_in(dir + "/pov"), (std::set<std::string>{"torus.pov", "torus.ini", "torus_2.png",
                                                           "torus_3.png", "torus_4.png"}));
  const Color white(1, 1, 1);
  std::vector<std::vector<bool>> masks;
  for (int f = 2; f <= 4; ++f) {
    const Image theirs = read_image(dir + "/pov/torus_" + std::to_string(f) + ".png");
    const Image ours = read_image(dir + "/frames/frame_000" + std::to_string(f) + ".png");
    ASSERT_EQ(theirs.width, 48);
    ASSERT_EQ(theirs.height, 48);
    masks.push_back(test::surface_mask(ours, white));
    EXPECT_GE(test::intersection_over_union(test::surface_mask(theirs, white), masks.back()), 0.97)
        << "frame " << f;
  }
  // The silhouettes move from frame to frame, so agreeing frame by frame means something.
  EXPECT_LT(test::intersection_over_union(masks[0], masks[2]), 0.9);
}

// The projection switches at frame 4 (orthographic, a window 4 high that shrinks to 3 by the
// last frame): the frames before it are the perspective picture, frame 4 the orthographic one;
// POV-Ray's frames of the exported animation switch there too.
TEST(CliKeyframes, KeyframesSwitchTheProjection) {
  const std::string dir = fresh_dir("keyframes-projection");
  const std::string scene = keyframed_scene(dir, R"([
    {"time": 0, "camera": {"projection": "perspective"}},
    {"frame": 4, "camera": {"projection": "orthographic", "ortho_height": 4}},
    {"time": 1, "camera": {"ortho_height": 3}, "ease": "linear"}])");
  auto r = run_command(
      zs("animate " + scene + " --frames 9 --size 48x48 --aa 1 --no-video -o " + dir + "/frames"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string still = " --size 48x48 --aa 1 -o " + dir;
  r = run_command(zs("render " + scene + still + "/persp.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_command(zs("render " + scene + " --projection ortho:4" + still + "/ortho.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(bytes_of(dir + "/persp.png") == bytes_of(dir + "/frames/frame_0003.png"));
  EXPECT_TRUE(bytes_of(dir + "/ortho.png") == bytes_of(dir + "/frames/frame_0004.png"));
  EXPECT_FALSE(bytes_of(dir + "/frames/frame_0004.png") ==
               bytes_of(dir + "/frames/frame_0008.png"));
  if (!have_povray()) GTEST_SKIP() << "povray is not installed";
  fs::create_directories(dir + "/pov");
  r = run_command(zs("export " + scene +
                     " --animate --frames 9 --frame-range 3-4 --size 48x48 "
                     "-o " +
                     dir + "/pov/torus.pov"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_command("cd " + dir + "/pov && povray -D -V torus.ini -A");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Color white(1, 1, 1);
  for (int f = 3; f <= 4; ++f) {
    const auto theirs =
        test::surface_mask(read_image(dir + "/pov/torus_" + std::to_string(f) + ".png"), white);
    const auto ours = test::surface_mask(
        read_image(dir + "/frames/frame_000" + std::to_string(f) + ".png"), white);
    EXPECT_GE(test::intersection_over_union(theirs, ours), 0.97) << "frame " << f;
  }
}

TEST(CliKeyframes, BadKeyframesAndFlagsTheyMakeMeaninglessExitTwo) {
  const std::string dir = fresh_dir("keyframes-bad");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"([{"time": 0.5, "params": {"R": 1}}, {"time": 0.2, "params": {"R": 0.8}}])",
       "/animation/keyframes/1: keyframes must come in increasing time"},
      {R"([{"time": 0, "params": {"q": 1}}])", "/animation/keyframes/0/params/q"},
      {R"([{"time": 0, "frame": 0}])", "/animation/keyframes/0: give either"},
      {R"([{"frame": 9, "params": {"R": 1}}])", "/animation/keyframes/0/frame"},
      {R"([{"time": 0, "ease": "bouncy"}])", "/animation/keyframes/0/ease"},
      {R"([{"time": 0, "camera": {"distance": 0}}])", "/animation/keyframes/0/camera/distance"},
      {R"([{"time": 0, "camera": {"elevation_deg": 95}}])",
       "/animation/keyframes/0/camera/elevation_deg"},
      {R"([{"time": 0, "camera": {"azimuth": 5}}])", "/animation/keyframes/0/camera/azimuth"},
      {R"([{"time": 0, "camera": {"projection": "fisheye"}}])",
       "/animation/keyframes/0/camera/projection"},
      {R"([{"time": 0, "camera": {"ortho_height": 0}}])",
       "/animation/keyframes/0/camera/ortho_height"},
      {R"({"time": 0})", "/animation/keyframes: expected a list"}};
  for (const auto& [keys, expected] : cases) {
    const std::string scene = keyframed_scene(dir, keys);
    for (const std::string& cmd :
         {"animate " + scene + " --frames 9 --size 32x32 --no-video -o " + dir + "/frames",
          "export " + scene + " --animate --frames 9 -o " + dir + "/a.pov"}) {
      const auto r = run_command(zs(cmd));
      EXPECT_EQ(r.exit_code, 2) << keys << "\n" << r.output;
      EXPECT_NE(r.output.find(expected), std::string::npos) << keys << "\n" << r.output;
    }
  }
  const std::string scene = keyframed_scene(dir, kKeyframes);
  for (const char* flags : {"--param r=0.1:0.2", "--param r=0.3", "--orbit 90", "--camera 10,10"}) {
    const auto r = run_command(zs("animate " + scene + " " + std::string(flags) +
                                  " --frames 9 --size 32x32 --no-video -o " + dir + "/frames"));
    EXPECT_EQ(r.exit_code, 2) << flags << "\n" << r.output;
    EXPECT_NE(r.output.find("keyframes animate it"), std::string::npos) << r.output;
  }
  // Export: --frames without --animate, --animate into a SURFER file, a surface POV-Ray cannot
  // animate (coefficients not polynomial in the parameter).
  for (const std::string& args :
       {"export " + scene + " --frames 9 -o " + dir + "/a.pov",
        "export " + scene + " --animate -o " + dir + "/a.jsurf",
        "export \"x^2 + y^2 + z^2 - sqrt(a)\" --param a=0.5:1 --animate -o " + dir + "/a.pov",
        "export \"x^2 + y^2 + z^2 - sqrt(a)\" --param a=0.1:1 --animate -o " + dir + "/a.pov",
        "export \"x^2 + y^2 + z^2 - 1/(1 + a^2)\" --param a=-1:1 --animate -o " + dir + "/a.pov"}) {
    const auto r = run_command(zs(args));
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
  }
  EXPECT_EQ(files_in(dir), (std::set<std::string>{"torus.json"}));
}

}  // namespace
}  // namespace zeroset
