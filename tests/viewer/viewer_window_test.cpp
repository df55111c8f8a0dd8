// `zeroset view` in a real window: a virtual X server (xvfb-run) with Mesa's software OpenGL,
// driven by scripts; the screenshots are checked for what a user would see.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include "render/image_masks.h"
#include "settings_values.h"
#include "support/file_bytes.h"
#include "support/run_command.h"
#include "support/xvfb.h"
#include "zeroset/floaters/settings.h"
#include "zeroset/io/image.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/render/overlay.h"
#include "zeroset/render/view.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset {
namespace {

using test::file_bytes;
using test::run_command;

// The viewer's default background (linear RGB), see viewer_state.cpp.
const Color kBackground(0.74, 0.76, 0.80);

using test::has_xvfb;

std::string temp_dir() {
  const auto d = std::filesystem::temp_directory_path() / "zeroset_viewer_window_test";
  std::filesystem::create_directories(d);
  return d.string();
}

std::string write_script(const std::string& name, const std::string& text) {
  const std::string path = temp_dir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

// `zeroset view ARGS` in a virtual 24-bit screen with software OpenGL.
test::CommandResult view(const std::string& args) {
  return test::run_viewer(ZEROSET_BINARY, args, "1280x1024");
}

// What fraction of the pixels in columns [x0, x1) show the surface, its front (orange) and
// its back (blue).
struct Census {
  double surface = 0, front = 0, back = 0;
};

Census census(const Image& img, int x0 = 0, int x1 = -1) {
  if (x1 < 0) x1 = img.width;
  const std::vector<bool> mask = test::surface_mask(img, kBackground);
  Census c;
  for (int y = 0; y < img.height; ++y)
    for (int x = x0; x < x1; ++x) {
      if (!mask[static_cast<size_t>(y) * img.width + x]) continue;
      const std::uint8_t* p = img.pixel(x, y);
      c.surface += 1;
      c.front += p[0] > p[2] + 40;
      c.back += p[2] > p[0] + 25;
    }
  const double n = static_cast<double>(img.height) * (x1 - x0);
  return {c.surface / n, c.front / n, c.back / n};
}

double changed_fraction(const Image& a, const Image& b, int x0 = 0) {
  if (a.width != b.width || a.height != b.height) return 1;
  long changed = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = x0; x < a.width; ++x) {
      const std::uint8_t* p = a.pixel(x, y);
      const std::uint8_t* q = b.pixel(x, y);
      changed += std::abs(p[0] - q[0]) + std::abs(p[1] - q[1]) + std::abs(p[2] - q[2]) > 30;
    }
  return static_cast<double>(changed) / (static_cast<double>(a.height) * (a.width - x0));
}

// Opens Kummer's surface in `mode`, lets the mode finish its work (`settle`), saves a
// screenshot, changes mu and saves another; checks both.
void check_mode(const std::string& mode, const std::string& setup, const std::string& settle) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  const std::string dir = temp_dir();
  const std::string a = dir + "/" + mode + "-a.png", b = dir + "/" + mode + "-b.png";
  std::filesystem::remove(a);
  std::filesystem::remove(b);
  const std::string script =
      write_script(mode + ".txt", "mode " + mode + "\n" + setup + settle + "screenshot " + a +
                                      "\nparam mu 2.2\n" + settle + "screenshot " + b + "\n");
  const auto r = view("kummer --no-ui --size 400x400 --script " + script);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image ia = read_image(a), ib = read_image(b);
  ASSERT_EQ(ia.width, 400);
  ASSERT_EQ(ia.height, 400);
  for (const Image* img : {&ia, &ib}) {
    const Census c = census(*img);
    EXPECT_GT(c.surface, 0.15) << mode;
    EXPECT_LT(c.surface, 0.9) << mode;
    EXPECT_GT(c.front, 0.03) << mode << ": the orange front side shows";
    EXPECT_GT(c.back, 0.01) << mode << ": the blue back side shows";
  }
  EXPECT_GT(changed_fraction(ia, ib), 0.05) << mode << ": mu = 2.2 looks different";
}

TEST(ViewerWindow, RayTracedKummerShowsBothSidesAndFollowsMu) {
  check_mode("raytrace", "", "wait\n");
}

TEST(ViewerWindow, MeshOfKummerShowsBothSidesAndFollowsMu) {
  check_mode("mesh", "mesh cells=40 max_steps=10\n", "wait\n");
}

TEST(ViewerWindow, FloatersOnKummerShowBothSidesAndFollowMu) {
  check_mode("floaters", "floaters max_count=3000 seed=2\n", "steps 150\n");
}

// F ≡ 0 for a field that is no polynomial: the log says what the commands say, and the
// ray-traced view is empty (interval arithmetic alone would draw the clip).
TEST(ViewerWindow, AVanishingFieldIsWarnedAboutAndDrawsNothing) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  const std::string dir = temp_dir();
  const std::string first = dir + "/vanishing-sin.png", second = dir + "/vanishing-exp.png";
  const std::string script =
      write_script("vanishing.txt", "mode raytrace\nwait\nscreenshot " + first +
                                        "\nequation 0*exp(x)\nwait\nscreenshot " + second + "\n");
  const auto r = view("'sin(x) - sin(x)' --clip sphere:2 --size 800x500 --script " + script);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* eq : {"warning: sin(x) - sin(x): F vanishes identically",
                         "warning: 0*exp(x): F vanishes identically"})
    EXPECT_NE(r.output.find(eq), std::string::npos) << r.output;
  for (const std::string& shot : {first, second})
    EXPECT_LT(census(read_image(shot), 360).surface, 0.001) << shot;
}

TEST(ViewerWindow, MalformedEquationShowsTheErrorAndTheViewerKeepsRunning) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  const std::string dir = temp_dir();
  const std::string bad = dir + "/bad-equation.png", good = dir + "/good-equation.png";
  const std::string script = write_script("typing.txt",
                                          "wait\n"
                                          "equation x^2 + y^2 +\n"
                                          "expect-error expected\n"
                                          "frames 3\n"
                                          "screenshot " +
                                              bad +
                                              "\n"
                                              "equation x^2 + y^2 - z^2\n"
                                              "wait\n"
                                              "screenshot " +
                                              good + "\n");
  const auto r = view("kummer --size 800x500 --script " + script);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("failed as expected"), std::string::npos) << r.output;
  const Image ib = read_image(bad), ig = read_image(good);
  // The panel (left 360 pixels) shows the diagnostics in red; the view still shows Kummer.
  auto red_pixels = [](const Image& img) {
    long n = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < 360; ++x) {
        const std::uint8_t* p = img.pixel(x, y);
        n += p[0] > 170 && p[1] < 130 && p[2] < 130;
      }
    return n;
  };
  EXPECT_GT(red_pixels(ib), 100) << "the error is shown";
  EXPECT_LT(red_pixels(ig), 10) << "and gone after a good equation";
  EXPECT_GT(census(ib, 360).surface, 0.15) << "the last good surface stays on screen";
  EXPECT_GT(census(ig, 360).surface, 0.05) << "the cone is drawn";
  EXPECT_GT(changed_fraction(ib, ig, 360), 0.1) << "the cone replaced Kummer's surface";
}

// The `stats` line a script printed (the last one).
nlohmann::json stats_line(const std::string& output) {
  std::istringstream lines(output);
  std::string line, last;
  while (std::getline(lines, line))
    if (line.starts_with("{\"")) last = line;
  return last.empty() ? nlohmann::json() : nlohmann::json::parse(last);
}

// A pixel of the singular overlay's colours as drawn (gamma encoded, lit): the crossing curves'
// green, the triple point's yellow. The surface's orange and blue and the background are
// neither.
bool is_green(const std::uint8_t* p) { return p[1] > p[0] + 60 && p[1] > p[2] + 60; }
bool is_yellow(const std::uint8_t* p) {
  return p[0] > 120 && p[1] > 0.85 * p[0] && p[2] < 0.5 * p[1];
}

long count_pixels(const Image& img, bool (*is)(const std::uint8_t*), double cx = 0, double cy = 0,
                  double radius = -1) {
  long n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if ((radius < 0 || std::hypot(x + 0.5 - cx, y + 0.5 - cy) <= radius) && is(img.pixel(x, y)))
        ++n;
  return n;
}

// Roman's surface cut open (docs/singular.md) in `mode` with the overlay off, then on: the
// panel's figures are the library's, the triple point shows where it projects, and the
// crossing curves show in their colour.
void check_singular_overlay(const std::string& mode, const std::string& settle) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  const std::string dir = temp_dir();
  const std::string off = dir + "/singular-" + mode + "-off.png";
  const std::string on = dir + "/singular-" + mode + "-on.png";
  const int size = 500;
  const std::string script = write_script(
      "singular-" + mode + ".txt",
      "clip sphere:0.6 plane:1,1,1,0.12\ncamera 35 25 2.4\nmode " + mode + "\n" + settle +
          "screenshot " + off + "\nsingular on\n" + settle + "stats\nscreenshot " + on + "\n");
  const auto r = view("roman --no-ui --size " + std::to_string(size) + "x" + std::to_string(size) +
                      " --script " + script);
  ASSERT_EQ(r.exit_code, 0) << r.output;

  Surface roman = make_surface(*find_catalog_entry("roman"));
  roman.clip = Clip();
  for (const char* spec : {"sphere:0.6", "plane:1,1,1,0.12"}) roman.clip.add(spec);
  const SingularSet expected = find_singular_set(roman);
  const nlohmann::json stats = stats_line(r.output);
  ASSERT_TRUE(stats.contains("singular")) << r.output;
  EXPECT_EQ(stats["singular"]["summary"], singular_set_summary(expected));
  EXPECT_EQ(stats["singular"]["curves"].size(), expected.curves.size());
  EXPECT_EQ(stats["singular"]["points"].size(), expected.points.size());

  const std::vector<Vec3> triples = expected.points_of(SingularPointKind::kTriple);
  ASSERT_EQ(triples.size(), 1u);
  Camera camera = roman.camera;
  camera.azimuth_deg = 35;
  camera.elevation_deg = 25;
  camera.distance = 2.4;
  const View v = View::from_camera(camera, roman.scene_radius(), size, size);
  double tx = 0, ty = 0, depth = 0;
  ASSERT_TRUE(v.project(triples[0], tx, ty, depth));
  // The sphere's radius on screen, and a pixel or two more.
  const double reach =
      SingularOverlay().point_radius_for(roman.scene_radius()) / (depth * v.pixel_angle()) + 2;
  const Image image_off = read_image(off), image_on = read_image(on);
  EXPECT_EQ(count_pixels(image_off, is_yellow, tx, ty, reach), 0) << mode;
  EXPECT_GE(count_pixels(image_on, is_yellow, tx, ty, reach), 3)
      << mode << ": the triple point at (" << tx << ", " << ty << ")";
  EXPECT_LT(count_pixels(image_off, is_green), 5) << mode;
  EXPECT_GT(count_pixels(image_on, is_green), 100) << mode << ": the crossing curves";
  const double changed = changed_fraction(image_off, image_on);
  EXPECT_GT(changed, 0.002) << mode;
  // Floaters go on moving between the two pictures; the other modes do not.
  if (mode != "floaters") {
    EXPECT_LT(changed, 0.1) << mode << ": only the overlay changed";
  }
}

TEST(ViewerWindow, SingularSetOverRayTracedRoman) { check_singular_overlay("raytrace", "wait\n"); }

TEST(ViewerWindow, SingularSetOverTheMeshOfRoman) {
  check_singular_overlay("mesh", "mesh cells=48 max_steps=20\nwait\n");
}

TEST(ViewerWindow, SingularSetOverTheFloatersOnRoman) {
  check_singular_overlay("floaters", "floaters max_count=3000 seed=2\nsteps 150\n");
}

TEST(ViewerWindow, SingularSetNotesForASquareAndAnUnboundedSurface) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  // The note is drawn in the panel in its own colour (ImGui colours are not gamma encoded).
  auto note_pixels = [](const Image& img) {
    long n = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < 360; ++x) {
        const std::uint8_t* p = img.pixel(x, y);
        n += std::abs(p[0] - 242) < 20 && std::abs(p[1] - 191) < 20 && p[2] < 120;
      }
    return n;
  };
  const std::string dir = temp_dir();
  struct Case {
    std::string surface, words, shot;
  };
  const Case cases[] = {
      {"'(x^2 + y^2 + z^2 - 1)^2' --clip sphere:2", "F = G^2", dir + "/singular-sheet.png"},
      {"'x*y'", "no bounded clip of its own", dir + "/singular-unbounded.png"},
      {"roman", "", dir + "/singular-no-note.png"}};
  for (const Case& c : cases) {
    const std::string script =
        write_script("singular-note.txt", "singular on\nwait\nstats\nscreenshot " + c.shot + "\n");
    const auto r = view(c.surface + " --size 800x500 --script " + script);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json stats = stats_line(r.output);
    ASSERT_TRUE(stats.contains("singular")) << r.output;
    const std::string note = stats["singular"]["note"];
    if (c.words.empty()) {
      EXPECT_TRUE(note.empty()) << note;
      EXPECT_LT(note_pixels(read_image(c.shot)), 10) << c.surface;
    } else {
      EXPECT_NE(note.find(c.words), std::string::npos) << note;
      EXPECT_GT(note_pixels(read_image(c.shot)), 100) << c.surface << ": the note is shown";
    }
    // The commands warn about a sheet where F = G^2; so does the viewer's log.
    EXPECT_EQ(r.output.find("warning: F = G^2") != std::string::npos, c.words == "F = G^2")
        << r.output;
  }
}

TEST(ViewerWindow, OpensASurferFile) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  const std::string dir = temp_dir();
  // SURFER's own syntax: the parameter a, a clip sphere of radius 10^0.3, a rotation.
  const std::string surface =
      write_script("cayley.jsurf",
                   "# a SURFER file\r\n"
                   "surface_equation=4*(x^2+y^2+z^2) + 16*x*y*z - a\r\n"
                   "surface_parameter_a=1\r\n"
                   "scale_factor=0.3\r\n"
                   "rotation_matrix=1 0 0 0 0 0.8 -0.6 0 0 0.6 0.8 0 0 0 0 1\r\n");
  const std::string shot = dir + "/jsurf.png";
  const auto r = view(surface + " --size 700x500 --script " +
                      write_script("jsurf.txt", "wait\nscreenshot " + shot + "\n"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The picture right of the panel shows the surface.
  EXPECT_GT(census(read_image(shot), 360).surface, 0.05);
}

TEST(ViewerWindow, MalformedScriptIsBadInputBeforeAWindowOpens) {
  const std::string script = write_script("bad-script.txt", "mode mesh\nparam mu\n");
  const auto r = run_command(std::string(ZEROSET_BINARY) + " view kummer --script " + script);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bad-script.txt:2"), std::string::npos) << r.output;
}

TEST(ViewerWindow, UnwritableScreenshotIsBadInputBeforeAWindowOpens) {
  const auto r = run_command(std::string(ZEROSET_BINARY) +
                             " view kummer --screenshot /nonexistent/dir/shot.png");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/dir"), std::string::npos) << r.output;
}

TEST(ViewerWindow, WithoutADisplayItSaysHowToRunHeadless) {
  const auto r = run_command("env -u DISPLAY -u WAYLAND_DISPLAY " + std::string(ZEROSET_BINARY) +
                             " view kummer --frames 1");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("xvfb-run"), std::string::npos) << r.output;
}

// ---- keyframes: recorded in the viewer, rendered by `zeroset animate` ---------------------------

const char* kTorusBase = R"j("equation": "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
  "parameters": {"R": 0.75, "r": 0.25}, "clip": ["sphere:2"],
  "camera": {"azimuth_deg": 30, "elevation_deg": 20})j";

// The frames `zeroset animate` renders of `scene` (7 frames, 48x48, one ray per pixel).
std::vector<std::string> animate_frames(const std::string& scene, const std::string& out) {
  std::filesystem::remove_all(out);
  const auto r = run_command(std::string(ZEROSET_BINARY) + " animate " + scene +
                             " --frames 7 --size 48x48 --aa 1 --no-video -o " + out);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::vector<std::string> frames;
  for (int f = 0; f < 7; ++f)
    frames.push_back(file_bytes(out + "/frame_000" + std::to_string(f) + ".png"));
  return frames;
}

TEST(ViewerWindow, KeyframesRecordedByAScriptAnimateAsTheSameKeyframesWrittenByHand) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  const std::string dir = temp_dir() + "/keyframes";
  std::filesystem::create_directories(dir);
  const std::string base = dir + "/base.json", hand = dir + "/hand.json";
  const std::string recorded = dir + "/recorded.json";
  std::filesystem::remove(recorded);
  std::ofstream(base) << "{" << kTorusBase << "}";
  // Two parameters and the camera at three keyframes; fov 30 and roll 0 are the camera's own.
  std::ofstream(hand) << "{" << kTorusBase << R"(, "animation": {"keyframes": [
    {"time": 0, "params": {"R": 0.8, "r": 0.3}, "ease": "in", "camera": {"azimuth_deg": 10,
     "elevation_deg": 20, "distance": 6, "roll_deg": 0, "fov_deg": 30}},
    {"time": 0.5, "params": {"R": 1.2, "r": 0.5}, "ease": "out", "camera": {"azimuth_deg": 50,
     "elevation_deg": 60, "distance": 5.5, "roll_deg": 0, "fov_deg": 30}},
    {"time": 1, "params": {"R": 1.2, "r": 0.45}, "ease": "linear", "camera": {"azimuth_deg": 100,
     "elevation_deg": 40, "distance": 5, "roll_deg": 0, "fov_deg": 30}}]}})";
  // Recorded out of order (the last keyframe first), with bad commands between: each is
  // refused and the script goes on.
  const std::string script =
      write_script("keyframes.txt",
                   "param R 0.8\nparam r 0.3\ncamera 10 20 6\nkeyframe add 0 in\n"
                   "param R 1.2\nparam r 0.45\ncamera 100 40 5\nkeyframe add 1 linear\n"
                   "param r 0.5\ncamera 50 60 5.5\nkeyframe add 0.5 in-out\n"
                   "keyframe add 0.5\nexpect-error already\n"
                   "keyframe move 1 0\nexpect-error increasing time\n"
                   "keyframe ease 1 bouncy\nexpect-error expected linear, in, out or in-out\n"
                   "keyframe delete 3\nexpect-error expected 0 to 2\n"
                   "keyframe add 2\nexpect-error must lie in [0, 1]\n"
                   "keyframe ease 1 out\n"
                   "keyframe time 0.25\nframes 3\nplay\nframes 5\npause\n"
                   "save-scene " +
                       recorded + "\n");
  const auto r = view(base + " --no-ui --size 200x200 --script " + script);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<std::string> ours = animate_frames(recorded, dir + "/recorded-frames");
  const std::vector<std::string> theirs = animate_frames(hand, dir + "/hand-frames");
  for (int f = 0; f < 7; ++f) {
    EXPECT_FALSE(ours[f].empty()) << f;
    EXPECT_TRUE(ours[f] == theirs[f]) << "frame " << f;
  }
  EXPECT_FALSE(ours[2] == ours[3]) << "the frames move";

  // A keyframed scene loaded in the viewer and saved: the same frames, and a second save is the
  // first byte for byte.
  const std::string once = dir + "/once.json", twice = dir + "/twice.json";
  std::filesystem::remove(once);
  std::filesystem::remove(twice);
  const std::string resave =
      write_script("resave.txt", "keyframe time 0.6\nframes 2\nsave-scene " + once + "\nload " +
                                     once + "\nsave-scene " + twice + "\n");
  const auto r2 = view(hand + " --no-ui --size 200x200 --script " + resave);
  ASSERT_EQ(r2.exit_code, 0) << r2.output;
  EXPECT_EQ(file_bytes(twice), file_bytes(once));
  const std::vector<std::string> resaved = animate_frames(once, dir + "/resaved-frames");
  for (int f = 0; f < 7; ++f) EXPECT_TRUE(resaved[f] == theirs[f]) << "frame " << f;
}

// A script sets every key of the scene file's "mesh" and "floaters" objects by `set`, as
// docs/viewer.md lists it, in the real window: save-scene writes each value, the mesh and the
// floaters still come, and bad values are refused with the scene file's words.
TEST(ViewerWindow, ScriptSetsEveryMeshAndFloaterSetting) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  const std::string dir = temp_dir();
  const std::string mesh_scene = dir + "/set-mesh.json", floater_scene = dir + "/set-floaters.json";
  std::filesystem::remove(mesh_scene);
  std::filesystem::remove(floater_scene);
  std::string text = "mode mesh\n";
  const nlohmann::json mesh_keys = mesh_settings_to_json(MeshSettings{});
  const nlohmann::json floater_keys = floater_settings_to_json(FloaterOptions{});
  for (const auto& [key, value] : mesh_keys.items())
    text += "set mesh." + key + " " + viewer::test::kMeshValues.at(key) + "\n";
  text += "wait\nstats\nsave-scene " + mesh_scene + "\n";
  text += "set mesh.grid fine\nexpect-error /mesh/grid: expected auto, dense or sparse\n";
  text += "mode floaters\n";
  for (const auto& [key, value] : floater_keys.items())
    text += "set floaters." + key + " " + viewer::test::kFloaterValues.at(key) + "\n";
  text += "steps 100\nstats\nsave-scene " + floater_scene + "\n";
  text += "set floaters.feedback -1\nexpect-error /floaters/feedback: must lie in [0, 66.6667)\n";
  text +=
      "set floaters.estimator_interval 0\n"
      "expect-error /floaters/estimator_interval: must lie in [1, 1000]\n";
  const auto r =
      view("kummer --no-ui --size 300x300 --script " + write_script("set-every-key.txt", text));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Two stats lines: the mesh's, then the floaters'.
  std::vector<nlohmann::json> stats;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);)
    if (line.starts_with("{\"")) stats.push_back(nlohmann::json::parse(line));
  ASSERT_EQ(stats.size(), 2u) << r.output;
  EXPECT_GT(stats[0]["mesh"]["triangles"].get<long>(), 500) << r.output;
  EXPECT_GT(stats[0]["mesh"]["improver_steps"].get<int>(), 0) << r.output;
  EXPECT_LE(stats[0]["mesh"]["improver_steps"].get<int>(),
            std::stoi(viewer::test::kMeshValues.at("improve")))
      << r.output;
  // With these values (clip projection off, so floaters that leave Kummer's clip die and the
  // rest refill it) the population cycles between about 3 and 75 floaters every 1,500 steps:
  // the count at a given step says only that floaters are there.
  EXPECT_GT(stats[1]["floaters"]["count"].get<long>(), 0) << r.output;
  EXPECT_LE(stats[1]["floaters"]["count"].get<long>(), 700) << r.output;
  for (const auto& [path, object, values] :
       {std::tuple{mesh_scene, "mesh", &viewer::test::kMeshValues},
        std::tuple{floater_scene, "floaters", &viewer::test::kFloaterValues}}) {
    std::ifstream in(path);
    ASSERT_TRUE(in) << path;
    const nlohmann::json saved = nlohmann::json::parse(in);
    for (const auto& [key, value] : *values)
      EXPECT_EQ(saved[object][key], viewer::test::expected_value(value)) << object << "." << key;
  }
}

// ---- live meshes: carried along an animation, rebuilt where the nodes change ------------------

// mu animates on Kummer in mesh mode: the stats lines show meshes carried from one value to the
// next (not rebuilt), and a jump across mu = 1, where 4 nodes become 16, rebuilds with that
// reason (docs/viewer.md, "Live meshes").
TEST(ViewerWindow, AnimatedMeshIsCarriedAndRebuiltWhereNodesAppear) {
  if (!has_xvfb()) GTEST_SKIP() << "xvfb-run is not installed (apt-get install xvfb)";
  const std::string text =
      "mode mesh\nmesh cells=24\nrange mu 1.2 2.0\nparam mu 1.3\nwait\n"
      "speed 0.05\nplay mu\nsleep 3\nstats\npause\n"
      "param mu 0.9\nwait\nparam mu 1.1\nwait\nstats\n";
  const auto r =
      view("kummer --no-ui --size 300x300 --script " + write_script("live-mesh.txt", text));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::vector<nlohmann::json> stats;
  std::istringstream lines(r.output);
  for (std::string line; std::getline(lines, line);)
    if (line.starts_with("{\"")) stats.push_back(nlohmann::json::parse(line));
  ASSERT_EQ(stats.size(), 2u) << r.output;
  const nlohmann::json& live = stats[0]["mesh"];
  EXPECT_GT(live["carried"].get<int>(), 2) << r.output;
  EXPECT_GT(live["updates_per_second"].get<double>(), 0) << r.output;
  EXPECT_GT(live["triangles"].get<long>(), 500) << r.output;
  const std::string last = live["last_update"].get<std::string>();
  EXPECT_TRUE(last.starts_with("carried in ") || last.starts_with("rebuilt: ")) << last;
  const nlohmann::json& jump = stats[1]["mesh"];
  EXPECT_GT(jump["rebuilt"].get<int>(), live["rebuilt"].get<int>()) << r.output;
  EXPECT_EQ(jump["last_update"].get<std::string>(), "rebuilt: singular points: 4 → 16") << r.output;
}

}  // namespace
}  // namespace zeroset
