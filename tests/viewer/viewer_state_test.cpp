// The viewer's state driven without a window, like a user would drive it: equations,
// parameters, animation, modes and their background jobs, scene files, and the guard that
// keeps every failure a status message.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "run_frames.h"
#include "support/temp_path.h"
#include "viewer_state.h"
#include "zeroset/error.h"
#include "zeroset/expr/field.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset::viewer {
namespace {

Scene kummer_scene() { return Scene{make_surface(*find_catalog_entry("kummer")), {}}; }

using test::run_until;

using zeroset::test::temp_path;

TEST(ViewerState, MalformedEquationShowsCaretAndKeepsTheLastGoodSurface) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  const std::string before = state.surface().field.source();
  EXPECT_FALSE(state.set_equation("x^2 + y^2 +"));
  EXPECT_TRUE(state.status().is_error);
  EXPECT_NE(state.equation_error().find('^'), std::string::npos) << state.equation_error();
  EXPECT_NE(state.equation_error().find("line 1"), std::string::npos) << state.equation_error();
  EXPECT_EQ(state.surface().field.source(), before);
  EXPECT_EQ(state.equation_text(), "x^2 + y^2 +") << "the field keeps what was typed";

  EXPECT_TRUE(state.set_equation("x^2 + y^2 - z^2"));
  EXPECT_TRUE(state.equation_error().empty());
  EXPECT_FALSE(state.status().is_error);
  EXPECT_EQ(state.surface().field.source(), "x^2 + y^2 - z^2");
}

// The commands' warning about the field (F ≡ 0 here) is a status line, so the log has it, and
// stays available to the panel while it holds.
TEST(ViewerState, WarnsLikeTheCommandsWhenFVanishesIdentically) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  EXPECT_TRUE(state.field_warning().empty()) << state.field_warning();
  std::vector<std::string> log;
  state.set_status_sink([&](const StatusLine& line) { log.push_back(line.text); });
  for (const char* eq : {"sin(x) - sin(x)", "0*exp(x)"}) {
    SCOPED_TRACE(eq);
    log.clear();
    ASSERT_TRUE(state.set_equation(eq));
    EXPECT_NE(state.field_warning().find("vanishes identically"), std::string::npos);
    const bool logged = std::any_of(log.begin(), log.end(), [](const std::string& l) {
      return l.rfind("warning: ", 0) == 0 && l.find("vanishes identically") != std::string::npos;
    });
    EXPECT_TRUE(logged);
  }
  ASSERT_TRUE(state.set_equation("x^2 + y^2 + z^2 - 1"));
  EXPECT_TRUE(state.field_warning().empty()) << state.field_warning();
}

// New parameter values alone are surveyed once they rest (or a second after the last survey
// while they keep moving), not at every value of an animation.
TEST(ViewerState, AParameterThatMakesFVanishIsWarnedAboutOnceItRests) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  ASSERT_TRUE(state.set_equation("a*(x^2 + y^2 + z^2 - 1)"));
  ASSERT_TRUE(state.set_parameter("a", 1));
  double t = 10;
  state.update(t);
  state.update(t += 1);
  EXPECT_TRUE(state.field_warning().empty()) << state.field_warning();
  ASSERT_TRUE(state.set_parameter("a", 0));
  EXPECT_TRUE(state.field_warning().empty()) << "surveyed at once, on the window's thread";
  state.update(t += 0.3);
  EXPECT_NE(state.field_warning().find("vanishes identically"), std::string::npos);
  // A moving parameter: a value every 50 ms is surveyed no more than once a second.
  for (int i = 1; i <= 10; ++i) {
    ASSERT_TRUE(state.set_parameter("a", 0.1 * i));
    state.update(t += 0.05);
  }
  EXPECT_NE(state.field_warning().find("vanishes identically"), std::string::npos)
      << "surveyed within half a second of the last survey";
  state.update(t += 0.3);
  EXPECT_TRUE(state.field_warning().empty()) << state.field_warning();
}

TEST(ViewerState, NewEquationKeepsTunedParametersAndStartsNewOnesAtOne) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  ASSERT_TRUE(state.set_parameter("mu", 2.0));
  ASSERT_TRUE(state.set_equation("x^2 + y^2 - mu*z^2 - a"));
  const Field& f = state.surface().field;
  EXPECT_EQ(f.parameter_values()[f.parameter_index("mu")], 2.0);
  EXPECT_EQ(f.parameter_values()[f.parameter_index("a")], 1.0);
  ASSERT_EQ(state.surface().ranges.size(), 2u);
  EXPECT_EQ(state.surface().ranges[1].name, "a");
  EXPECT_NE(state.status().text.find("a start at 1"), std::string::npos) << state.status().text;
  EXPECT_TRUE(state.surface().clip.is_bounded());
}

TEST(ViewerState, ParameterOutsideItsRangeWidensTheRange) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  ASSERT_TRUE(state.set_parameter("mu", 2e6));
  EXPECT_EQ(state.surface().ranges[0].max, 2e6);
  EXPECT_EQ(state.surface().field.parameter_values()[0], 2e6);
}

TEST(ViewerState, BadActionsBecomeErrorStatusesNotExceptions) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  EXPECT_FALSE(state.set_parameter("nu", 1.0));
  EXPECT_NE(state.status().text.find("no parameter 'nu'"), std::string::npos);
  EXPECT_FALSE(state.set_parameter("mu", std::nan("")));
  EXPECT_FALSE(state.set_parameter_range("mu", 2, 1));
  EXPECT_FALSE(state.select_catalog("nosuchsurface"));
  EXPECT_NE(state.status().text.find("kummer"), std::string::npos) << "lists the catalog";
  EXPECT_FALSE(state.set_clip_specs({"plane:0,0,1,0"}));  // unbounded
  EXPECT_FALSE(state.load_scene(temp_path("missing.json")));
  EXPECT_FALSE(state.set_speed(-1));
  EXPECT_TRUE(state.status().is_error);
  EXPECT_EQ(state.surface().name, "kummer");
  EXPECT_EQ(state.surface().clip.to_specs(true), std::vector<std::string>{"sphere:3"});
}

TEST(ViewerState, NoCommandLineThrowsWhateverItSays) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  const std::vector<std::string> lines = {"",
                                          "# comment",
                                          "param",
                                          "param mu",
                                          "param mu x",
                                          "param mu 1e999",
                                          "mode nothing",
                                          "clip sphere:-1",
                                          "clip box:0",
                                          "floaters max_count=0",
                                          "floaters radius=-1",
                                          "floaters radius_adapt=best",
                                          "floaters what",
                                          "mesh cells=2",
                                          "camera 0 0 -1",
                                          "zoom 0",
                                          "color front 2 0 0",
                                          "color middle 0 0 0",
                                          "equation (((",
                                          "equation x^",
                                          "save-scene /nonexistent/dir/s.json",
                                          "save-mesh out.xyz",
                                          "save-floaters f.ply",
                                          "frames 3",
                                          "range mu 1 1",
                                          "draw cubes",
                                          "lights up",
                                          "speed 0",
                                          "play nu",
                                          "load"};
  for (const auto& line : lines) EXPECT_NO_THROW(state.command(line)) << line;
  // Random bytes, too.
  std::mt19937 rng(7);
  for (int i = 0; i < 300; ++i) {
    std::string line;
    const int n = static_cast<int>(rng() % 40);
    for (int k = 0; k < n; ++k) line += static_cast<char>(32 + rng() % 95);
    if (i % 3 == 0) line = "equation " + line;
    EXPECT_NO_THROW(state.command(line)) << line;
  }
  EXPECT_NO_THROW(state.update(0.0));
}

TEST(ViewerState, CommandsSetWhatTheyName) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  EXPECT_TRUE(state.command("mode mesh"));
  EXPECT_EQ(state.mode(), Mode::kMesh);
  EXPECT_TRUE(state.command("param mu 2.25"));
  EXPECT_EQ(state.surface().field.parameter_values()[0], 2.25);
  EXPECT_TRUE(state.command("camera 10 20 9"));
  EXPECT_EQ(state.camera().azimuth_deg, 10);
  EXPECT_EQ(state.camera().elevation_deg, 20);
  EXPECT_EQ(state.camera().distance, 9);
  EXPECT_TRUE(state.command("clip sphere:2.5 plane:0,0,1,1"));
  EXPECT_EQ(state.surface().clip.spheres.size(), 1u);
  EXPECT_EQ(state.surface().clip.planes.size(), 1u);
  EXPECT_TRUE(state.command("floaters max_count=500 radius=0.1 cos_weight=off radius_adapt=wh"));
  EXPECT_EQ(state.floater_options().max_count, 500u);
  EXPECT_EQ(state.floater_options().radius, 0.1);
  EXPECT_FALSE(state.floater_options().cos_weight);
  EXPECT_EQ(state.floater_options().radius_adapt, RadiusAdapt::kWitkinHeckbert);
  EXPECT_TRUE(state.command("mesh cells=40 improve=off"));
  EXPECT_EQ(state.mesh_settings().cells, 40);
  EXPECT_FALSE(state.mesh_settings().improve);
  EXPECT_TRUE(state.command("wireframe on"));
  EXPECT_TRUE(state.display().wireframe);
  EXPECT_TRUE(state.command("lights fixed"));
  EXPECT_FALSE(state.lights_follow_camera());
  EXPECT_TRUE(state.command("catalog cone"));
  EXPECT_EQ(state.surface().name, "cone");
  EXPECT_TRUE(state.command("equation x^2 + y^2 = z^2"));
  EXPECT_EQ(state.surface().field.source(), "x^2 + y^2 = z^2");
  EXPECT_FALSE(state.command("frames 3")) << "frame-loop commands need a script";
}

TEST(ViewerState, AnimationBouncesInsideTheRangeWhenLooping) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  ASSERT_TRUE(state.set_parameter_range("mu", 1.0, 2.0));
  ASSERT_TRUE(state.set_speed(0.5));  // half the range per second
  ASSERT_TRUE(state.play("mu"));
  double t = 0, lo = 10, hi = -10;
  int direction_changes = 0, last_direction = state.animation().direction;
  for (int i = 0; i < 400; ++i) {  // 8 seconds at 50 frames per second: two round trips
    t += 0.02;
    state.update(t);
    const double v = state.surface().field.parameter_values()[0];
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    direction_changes += state.animation().direction != last_direction;
    last_direction = state.animation().direction;
  }
  EXPECT_GE(lo, 1.0);
  EXPECT_LE(hi, 2.0);
  EXPECT_LT(lo, 1.05);
  EXPECT_GT(hi, 1.95);
  EXPECT_GE(direction_changes, 3);
  EXPECT_TRUE(state.animation().is_playing);
}

TEST(ViewerState, AnimationWithoutLoopStopsAtTheEnd) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  ASSERT_TRUE(state.set_parameter_range("mu", 1.0, 2.0));
  ASSERT_TRUE(state.set_speed(1.0));
  state.set_loop(false);
  ASSERT_TRUE(state.play());
  for (int i = 1; i <= 100; ++i) state.update(0.05 * i);
  EXPECT_FALSE(state.animation().is_playing);
  EXPECT_EQ(state.surface().field.parameter_values()[0], 2.0);
  // Playing again runs back.
  ASSERT_TRUE(state.play());
  state.update(5.05);
  EXPECT_LT(state.surface().field.parameter_values()[0], 2.0);
}

TEST(ViewerState, RayTracedPreviewRefinesToFullResolution) {
  ViewerState state(kummer_scene(), Mode::kRaytrace, 2);
  // Large enough that the full picture takes far longer than the coarse one and a poll.
  state.set_viewport(960, 640);
  std::vector<int> divisors;
  ASSERT_TRUE(run_until(state, [&] {
    const auto p = state.preview();
    if (p && (divisors.empty() || divisors.back() != p->divisor)) divisors.push_back(p->divisor);
    return state.is_settled();
  }));
  const auto p = state.preview();
  EXPECT_EQ(p->divisor, 1);
  EXPECT_EQ(p->image.width, 960);
  EXPECT_EQ(p->image.height, 640);
  EXPECT_GT(p->stats.hits, 960 * 640 / 10);
  EXPECT_GE(divisors.front(), 2) << "a coarse picture comes first";
  // Any change starts again from a coarse picture.
  state.orbit(30, 0);
  EXPECT_FALSE(state.is_settled());
  ASSERT_TRUE(run_until(state, [&] { return state.is_settled(); }));
}

TEST(ViewerState, MeshModeDeliversAMeshOnTheSurface) {
  ViewerState state(kummer_scene(), Mode::kMesh, 2);
  ASSERT_TRUE(state.command("mesh cells=32 max_steps=5"));
  ASSERT_TRUE(run_until(
      state, [&] { return state.is_settled(); }, 60));
  const auto frame = state.mesh();
  ASSERT_TRUE(frame);
  EXPECT_EQ(frame->improver_steps, 5);
  const Mesh& m = frame->mesh;
  ASSERT_GT(m.triangle_count(), 1000u);
  ASSERT_EQ(m.normals.size(), m.positions.size());
  Evaluator ev(state.surface().field);
  double worst = 0;
  for (const Vec3& p : m.positions) {
    Vec3 g;
    const double f = ev.value_gradient(p, g);
    if (g.norm() > 1e-3) worst = std::max(worst, std::abs(f) / g.norm());
  }
  EXPECT_LT(worst, 0.05) << "vertices lie near F = 0 (cell size 0.19)";
}

TEST(ViewerState, AParameterChangeCarriesTheMeshAndAJumpAcrossNodesRebuildsIt) {
  // The carry takes a few steps of the paper's improver whichever improver is chosen; then the
  // paper's improver goes on to rest with the same vertices, the remesher remeshes the carried
  // mesh to rest as one final frame.
  for (const std::string improver : {"paper", "remesh"}) {
    SCOPED_TRACE("improver " + improver);
    ViewerState state(kummer_scene(), Mode::kMesh, 2);
    ASSERT_TRUE(state.command("mesh cells=24 max_steps=30 improver=" + improver));
    ASSERT_TRUE(run_until(
        state, [&] { return state.is_settled(); }, 60));
    const size_t vertices = state.mesh()->mesh.vertex_count();
    EXPECT_EQ(state.stats().mesh_update, "built");
    // A small step of mu: the same vertices, carried onto the new surface, then improved to
    // rest.
    ASSERT_TRUE(state.set_parameter("mu", 1.52));
    ASSERT_TRUE(run_until(
        state, [&] { return state.is_settled(); }, 60));
    const auto frame = state.mesh();
    ASSERT_TRUE(frame);
    EXPECT_TRUE(frame->carried);
    EXPECT_TRUE(frame->is_final);
    if (improver == "paper") {
      EXPECT_EQ(frame->mesh.vertex_count(), vertices);
    }
    EXPECT_TRUE(state.stats().mesh_update.starts_with("carried in ")) << state.stats().mesh_update;
    EXPECT_EQ(state.stats().mesh_carried, 1u);
    Evaluator ev(state.surface().field);
    double worst = 0;
    for (const Vec3& p : frame->mesh.positions) {
      Vec3 g;
      const double f = ev.value_gradient(p, g);
      if (g.norm() > 1e-3) worst = std::max(worst, std::abs(f) / g.norm());
    }
    EXPECT_LT(worst, 1e-6);
    // Across mu = 1 twelve nodes vanish: made again from scratch, and the stats say why.
    ASSERT_TRUE(state.set_parameter("mu", 0.9));
    ASSERT_TRUE(run_until(
        state, [&] { return state.is_settled(); }, 60));
    EXPECT_FALSE(state.mesh()->carried);
    EXPECT_EQ(state.stats().mesh_update, "rebuilt: singular points: 16 → 4");
    EXPECT_EQ(state.stats().mesh_rebuilt, 1u);
    // Another setting is never carried across.
    ASSERT_TRUE(state.command("mesh cells=20"));
    ASSERT_TRUE(run_until(
        state, [&] { return state.is_settled(); }, 60));
    EXPECT_EQ(state.stats().mesh_update, "built");
  }
}

TEST(ViewerState, FloatersFollowTheAnimatedParameter) {
  // A sphere of radius r: the floaters must stay on it while r grows.
  Scene scene;
  scene.surface = surface_from_equation("x^2 + y^2 + z^2 - r^2");
  scene.surface.field.set_parameter("r", 1.0);
  scene.surface.ranges = {{"r", 1.0, 1.5}};
  scene.surface.clip = Clip::sphere(2);
  ViewerState state(scene, Mode::kFloaters, 2);
  ASSERT_TRUE(state.command("floaters max_count=400 seed=3"));
  ASSERT_TRUE(run_until(state, [&] { return state.stats().floater_steps >= 60; }));
  ASSERT_TRUE(state.set_speed(0.5));
  state.set_loop(false);
  ASSERT_TRUE(state.play("r"));
  ASSERT_TRUE(run_until(state, [&] { return !state.animation().is_playing; }));
  // The animation runs by the clock: a slow build (the sanitizers) takes fewer steps during
  // it, so the floaters trail further at its end. They must be back on the sphere within 200
  // steps after it, and after at least 20.
  const std::size_t steps = state.stats().floater_steps;
  double worst = 0;
  std::size_t count = 0;
  const auto back_on_sphere = [&] {
    const auto f = state.floaters();
    if (!f) return false;
    count = f->positions.size();
    worst = 0;
    for (const Vec3& p : f->positions) worst = std::max(worst, std::abs(p.norm() - 1.5));
    return worst < 0.05 && state.stats().floater_steps >= steps + 20;
  };
  ASSERT_TRUE(run_until(
      state, [&] { return back_on_sphere() || state.stats().floater_steps >= steps + 200; }));
  EXPECT_GT(count, 50u);
  EXPECT_LT(worst, 0.05);
  EXPECT_GT(state.stats().steps_per_second, 0);
}

TEST(ViewerState, SceneRoundTripKeepsSurfaceCameraAndSettings) {
  ViewerState a(kummer_scene(), Mode::kRaytrace);
  ASSERT_TRUE(a.command("param mu 2.1"));
  ASSERT_TRUE(a.command("range mu 1.2 2.4"));
  ASSERT_TRUE(a.command("camera 40 25 11"));
  ASSERT_TRUE(a.command("clip sphere:2.5"));
  ASSERT_TRUE(a.command("mode floaters"));
  ASSERT_TRUE(
      a.command("floaters max_count=1234 cos_weight=off radius_adapt=curvature snap_to_nodes=off"));
  ASSERT_TRUE(a.command("mesh cells=77"));
  ASSERT_TRUE(a.command("speed 0.3"));
  ASSERT_TRUE(a.command("draw points"));
  ASSERT_TRUE(a.command("color front 0.1 0.8 0.2"));
  const std::string path = temp_path("roundtrip.json");
  ASSERT_TRUE(a.save_scene(path)) << a.status().text;

  const Scene read = read_scene(path);  // what the CLI reads
  EXPECT_EQ(read.surface.field.parameter_values()[0], 2.1);
  ViewerState b(read, std::nullopt);
  EXPECT_EQ(b.mode(), Mode::kFloaters);
  EXPECT_EQ(b.surface().ranges[0].min, 1.2);
  EXPECT_EQ(b.surface().ranges[0].max, 2.4);
  EXPECT_EQ(b.camera().azimuth_deg, 40);
  EXPECT_EQ(b.camera().distance, 11);
  EXPECT_EQ(b.surface().clip.to_specs(), std::vector<std::string>{"sphere:2.5"});
  EXPECT_EQ(b.floater_options().max_count, 1234u);
  EXPECT_FALSE(b.floater_options().cos_weight);
  EXPECT_EQ(b.floater_options().radius_adapt, RadiusAdapt::kCurvature);
  EXPECT_FALSE(b.floater_options().snap_to_nodes);
  EXPECT_EQ(b.mesh_settings().cells, 77);
  EXPECT_EQ(b.animation().speed, 0.3);
  EXPECT_TRUE(b.display().draw_points);
  EXPECT_EQ(b.look().front.diffuse, Color(0.1, 0.8, 0.2));
}

TEST(ViewerState, MalformedSceneSettingsAreBadInputNamingTheEntry) {
  Scene scene = kummer_scene();
  scene.settings = nlohmann::json::parse(R"({"floaters": {"max_count": "many"}})");
  try {
    ViewerState state(scene, std::nullopt, 0, "saved.json");
    FAIL() << "expected BadInput";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("saved.json: /floaters/max_count"), std::string::npos)
        << e.what();
  }
}

TEST(ViewerState, SavingWithTheWrongExtensionWritesNothing) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  const std::string path = temp_path("scene.txt");
  std::filesystem::remove(path);
  EXPECT_FALSE(state.save_scene(path));
  EXPECT_FALSE(std::filesystem::exists(path));
  EXPECT_FALSE(state.save_floaters(temp_path("f.ply"))) << "no floaters yet";
  EXPECT_FALSE(state.save_mesh(temp_path("m.ply"))) << "no mesh yet";
}

TEST(ViewerState, RangesFollowTheFieldWhateverTheSceneSays) {
  Scene scene;
  scene.surface = surface_from_equation("a*x + b*y - z");
  scene.surface.field.set_parameter("a", 1.0);
  scene.surface.field.set_parameter("b", 7.0);
  scene.surface.ranges = {{"b", 0.0, 1.0}};  // out of order, incomplete, value outside
  scene.surface.clip = Clip::sphere(1);
  ViewerState state(scene, Mode::kRaytrace);
  const auto& r = state.surface().ranges;
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].name, "a");
  EXPECT_EQ(r[1].name, "b");
  EXPECT_EQ(state.surface().field.parameter_values()[1], 7.0);
  EXPECT_EQ(r[1].max, 7.0);
  EXPECT_TRUE(state.set_parameter("b", 0.5));
}

TEST(ViewerState, AParameterWithoutValueIsBadInput) {
  Scene scene;
  scene.surface = surface_from_equation("x^2 + y^2 - k");
  scene.surface.clip = Clip::sphere(1);
  EXPECT_THROW(ViewerState(scene, Mode::kRaytrace), BadInput);
}

TEST(ViewerState, UnboundedClipIsReplacedByASphere) {
  Scene scene;
  scene.surface = surface_from_equation("x*y*z - 0.1");
  ViewerState state(scene, Mode::kRaytrace);
  EXPECT_TRUE(state.surface().clip.is_bounded());
  EXPECT_NE(state.status().text.find("sphere:2"), std::string::npos);
}

TEST(ViewerState, LightsStayInPlaceWhenTheyStopFollowingTheCamera) {
  ViewerState state(kummer_scene(), Mode::kRaytrace);
  const View v = state.view();
  const Vec3 world = v.camera_to_world(state.look().lights[0].direction).normalized();
  state.set_lights_follow_camera(false);
  EXPECT_LT((state.look().lights[0].direction.normalized() - world).norm(), 1e-12);
  state.set_lights_follow_camera(true);
  EXPECT_LT((v.camera_to_world(state.look().lights[0].direction).normalized() - world).norm(),
            1e-12);
}

}  // namespace
}  // namespace zeroset::viewer
