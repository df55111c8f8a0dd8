// The singular set in the viewer without a window: the toggle, the background search and what
// it reports for the current surface, parameters and clip, the notes for surfaces the search
// cannot draw, scene files, and the triangles the GL view draws.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <thread>

#include "run_frames.h"
#include "singular_geometry.h"
#include "support/temp_path.h"
#include "viewer_state.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset::viewer {
namespace {

using test::run_until;
using test::seconds_now;

bool has_current_set(const ViewerState& s) { return s.singular() && s.singular_is_current(); }

Scene catalog_scene(const char* name) { return Scene{make_surface(*find_catalog_entry(name)), {}}; }

// Parameters start at 0.5.
Scene equation_scene(const std::string& equation, const Clip& clip) {
  Surface s;
  s.field = std::move(*parse_field(equation).field);
  for (const std::string& name : s.field.parameter_names()) s.field.set_parameter(name, 0.5);
  s.clip = clip;
  return Scene{std::move(s), {}};
}

using zeroset::test::temp_path;

TEST(ViewerSingular, RomanShowsWhatTheLibraryFinds) {
  for (const Mode mode : {Mode::kRaytrace, Mode::kMesh, Mode::kFloaters}) {
    ViewerState state(catalog_scene("roman"), mode, 1);
    EXPECT_EQ(state.singular(), nullptr) << "off by default";
    ASSERT_TRUE(state.command("singular on"));
    ASSERT_TRUE(run_until(state, [&] { return has_current_set(state); }));
    const SingularSet expected = find_singular_set(state.surface());
    const SingularFrame& got = *state.singular();
    EXPECT_EQ(got.summary, singular_set_summary(expected));
    for (const CurveKind k : {CurveKind::kCrossing, CurveKind::kIsolated, CurveKind::kDegenerate})
      EXPECT_EQ(got.set.count(k), expected.count(k)) << to_string(k);
    const std::vector<Vec3> triples = got.set.points_of(SingularPointKind::kTriple);
    ASSERT_EQ(triples.size(), expected.points_of(SingularPointKind::kTriple).size());
    // The three double lines of docs/singular.md meet in the triple point at the origin.
    EXPECT_EQ(got.set.count(CurveKind::kCrossing), 3);
    ASSERT_EQ(triples.size(), 1u);
    EXPECT_LT(triples[0].norm(), 1e-9);
    EXPECT_TRUE(got.note.empty()) << got.note;
    const nlohmann::json stats = state.stats().to_json();
    ASSERT_TRUE(stats.contains("singular"));
    EXPECT_EQ(stats["singular"]["summary"], got.summary);
    EXPECT_EQ(stats["singular"]["curves"].size(), expected.curves.size());
    if (mode == Mode::kRaytrace) {
      // The picture that settles is traced with this set in it.
      ASSERT_TRUE(run_until(state, [&] { return state.is_settled(); }));
      EXPECT_EQ(state.preview()->singular, state.singular());
    }
  }
}

TEST(ViewerSingular, ParameterAndClipChangesSearchAgain) {
  // Two planes crossing along the line x = a, y = -a.
  ViewerState state(equation_scene("(x - a)*(y + a)", Clip::sphere(2)), Mode::kMesh, 1);
  ASSERT_TRUE(state.command("param a 0.5"));
  ASSERT_TRUE(state.command("singular on"));
  auto line_at = [&](double a) {
    if (!has_current_set(state)) return false;
    const SingularSet& set = state.singular()->set;
    if (set.count(CurveKind::kCrossing) != 1) return false;
    for (const Vec3& p : set.curves[0].points)
      if (std::abs(p.x() - a) > 1e-9 || std::abs(p.y() + a) > 1e-9) return false;
    return true;
  };
  ASSERT_TRUE(run_until(state, [&] { return line_at(0.5); }));
  ASSERT_TRUE(state.command("param a -0.3"));
  EXPECT_FALSE(state.singular_is_current()) << "the shown set is the old parameter's";
  EXPECT_NE(state.singular(), nullptr) << "and stays on screen until the new one is found";
  ASSERT_TRUE(run_until(state, [&] { return line_at(-0.3); }));

  // A new clip: the old set is not drawn on it, and the new one ends on the new clip.
  ASSERT_TRUE(state.command("clip sphere:1"));
  EXPECT_EQ(state.singular(), nullptr);
  ASSERT_TRUE(run_until(state, [&] { return line_at(-0.3); }));
  for (const Vec3& p : state.singular()->set.curves[0].points) EXPECT_LE(p.norm(), 1 + 1e-9);

  // A new equation: the same.
  ASSERT_TRUE(state.command("equation x*y*z"));
  EXPECT_EQ(state.singular(), nullptr);
  ASSERT_TRUE(run_until(state, [&] { return has_current_set(state); }));
  EXPECT_EQ(state.singular()->set.count(CurveKind::kCrossing), 3) << state.singular()->summary;
}

TEST(ViewerSingular, AnAnimationKeepsTheSetComing) {
  // While a parameter moves every frame, searches finish and show: none is cancelled before
  // its result.
  ViewerState state(equation_scene("(x - a)*(y + a)", Clip::sphere(2)), Mode::kMesh, 1);
  ASSERT_TRUE(state.command("singular on"));
  ASSERT_TRUE(state.command("range a -1 1"));
  ASSERT_TRUE(state.command("speed 0.5"));
  ASSERT_TRUE(state.play("a"));
  std::shared_ptr<const SingularFrame> last;
  int sets = 0;
  // Three new sets, however slow the machine (a sanitizer build): the limit only ends a hang.
  const double end = seconds_now() + 30;
  while (seconds_now() < end && sets < 3) {
    state.update(seconds_now());
    if (state.singular() && state.singular() != last) {
      last = state.singular();
      ++sets;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  state.pause();
  EXPECT_GE(sets, 3) << "new sets while the parameter moved";
  ASSERT_TRUE(run_until(state, [&] { return has_current_set(state); }));
  const double a = state.surface().field.parameter_values()[0];
  ASSERT_EQ(state.singular()->set.count(CurveKind::kCrossing), 1);
  EXPECT_NEAR(state.singular()->set.curves[0].points[0].x(), a, 1e-9);
}

TEST(ViewerSingular, SingularSheetIsReportedNotDrawn) {
  // F = G^2 with G a sphere: grad F vanishes on the whole sphere.
  ViewerState state(equation_scene("(x^2 + y^2 + z^2 - 1)^2", Clip::sphere(2)), Mode::kRaytrace, 1);
  ASSERT_TRUE(state.command("singular on"));
  ASSERT_TRUE(run_until(state, [&] { return has_current_set(state); }));
  const SingularFrame& f = *state.singular();
  EXPECT_TRUE(f.set.has_singular_sheet);
  EXPECT_EQ(f.summary, singular_set_summary(f.set));
  EXPECT_NE(f.note.find("F = G^2"), std::string::npos) << f.note;
  EXPECT_TRUE(run_until(state, [&] { return state.is_settled(); }));
}

TEST(ViewerSingular, UnboundedSurfaceSaysWhereItWasSearched) {
  // The viewer gives a surface without a bounded clip a sphere; the note says so.
  ViewerState state(equation_scene("x*y", Clip()), Mode::kRaytrace, 1);
  ASSERT_TRUE(state.command("singular on"));
  ASSERT_TRUE(run_until(state, [&] { return has_current_set(state); }));
  const SingularFrame& f = *state.singular();
  EXPECT_NE(f.note.find("no bounded clip of its own"), std::string::npos) << f.note;
  EXPECT_NE(f.note.find("sphere:2"), std::string::npos) << f.note;
  EXPECT_EQ(f.set.count(CurveKind::kCrossing), 1) << f.summary;
  // A clip of the user's own: no note.
  ASSERT_TRUE(state.command("clip sphere:1.5"));
  ASSERT_TRUE(run_until(state, [&] { return has_current_set(state); }));
  EXPECT_TRUE(state.singular()->note.empty()) << state.singular()->note;

  // The search itself, given a surface with no bounded clip, says it needs one.
  Surface open = equation_scene("x*y", Clip()).surface;
  SingularFrame frame;
  ASSERT_NO_THROW(frame = find_singular_frame(open, false));
  EXPECT_NE(frame.note.find("needs a bounded clip"), std::string::npos) << frame.note;
  EXPECT_TRUE(frame.summary.empty());
  EXPECT_TRUE(frame.set.empty());
}

TEST(ViewerSingular, ToggleIsACommandAndASceneSetting) {
  ViewerState state(catalog_scene("whitney"), Mode::kMesh, 1);
  EXPECT_FALSE(state.command("singular maybe"));
  EXPECT_FALSE(state.command("singular"));
  ASSERT_TRUE(state.command("singular on"));
  EXPECT_TRUE(state.display().show_singular);
  ASSERT_TRUE(run_until(state, [&] { return has_current_set(state); }));
  const std::string path = temp_path("whitney.json");
  ASSERT_TRUE(state.save_scene(path));
  EXPECT_EQ(read_scene(path).settings["viewer"]["show_singular"], true);
  ASSERT_TRUE(state.command("singular off"));
  EXPECT_EQ(state.singular(), nullptr);
  EXPECT_FALSE(state.stats().to_json().contains("singular"));
  ASSERT_TRUE(state.load_scene(path));
  EXPECT_TRUE(state.display().show_singular);
  ASSERT_TRUE(run_until(state, [&] { return has_current_set(state); }));
  EXPECT_EQ(state.singular()->set.points_of(SingularPointKind::kPinch).size(), 1u)
      << state.singular()->summary;

  Scene bad = catalog_scene("whitney");
  bad.settings = nlohmann::json::parse(R"({"viewer": {"show_singular": 3}})");
  EXPECT_THROW(ViewerState(bad, Mode::kMesh, 1), BadInput);
}

TEST(ViewerSingular, GeometryWrapsTheCurvesAndPoints) {
  const Surface roman = make_surface(*find_catalog_entry("roman"));
  const SingularSet set = find_singular_set(roman);
  const SingularOverlay style;
  const double radius = roman.scene_radius();
  const OverlayGeometry g = singular_overlay_geometry(set, style, radius);
  ASSERT_GT(g.vertex_count(), 0u);
  ASSERT_EQ(g.indices.size() % 3, 0u);
  for (const std::uint32_t i : g.indices) ASSERT_LT(i, g.vertex_count());
  // Every vertex lies near the set (on a tube or a sphere), with a unit normal.
  auto vertex = [&](const OverlayGeometry& geometry, size_t v) {
    const float* f = &geometry.vertices[6 * v];
    return std::pair(Vec3(f[0], f[1], f[2]), Vec3(f[3], f[4], f[5]));
  };
  const double ball = style.point_radius_for(radius);
  for (size_t v = 0; v < g.vertex_count(); ++v) {
    const auto [p, n] = vertex(g, v);
    ASSERT_NEAR(n.norm(), 1, 1e-5);
    ASSERT_LT(set.distance(p), 1.001 * ball) << v;
  }
  // A closed curve (no end caps): its tube is round, of the tube radius, normals outwards.
  SingularSet circle;
  circle.curves.push_back({CurveKind::kIsolated, {}, true});
  for (int i = 0; i <= 40; ++i)
    circle.curves[0].points.push_back(
        Vec3(std::cos(i * std::numbers::pi / 20), std::sin(i * std::numbers::pi / 20), 0));
  const OverlayGeometry ring = singular_overlay_geometry(circle, style, 2);
  const double tube = style.tube_radius_for(2);
  ASSERT_GT(ring.vertex_count(), 0u);
  for (size_t v = 0; v < ring.vertex_count(); ++v) {
    const auto [p, n] = vertex(ring, v);
    const double d = circle.distance(p);
    ASSERT_GT(d, 0.99 * tube) << v;
    ASSERT_LT(d, 1.001 * tube) << v;
    ASSERT_LT(circle.distance(p - 0.5 * tube * n), d) << "the normal points outwards";
  }
  // One batch per colour present, in the overlay's colours.
  int crossing = 0, triple = 0;
  for (const auto& b : g.batches) {
    crossing += b.color == style.crossing;
    triple += b.color == style.triple;
    EXPECT_GT(b.count, 0u);
  }
  EXPECT_EQ(crossing, set.count(CurveKind::kCrossing) > 0 ? 1 : 0);
  EXPECT_EQ(triple, set.points_of(SingularPointKind::kTriple).empty() ? 0 : 1);

  // A straight curve costs as much with 50 vertices as with 2.
  SingularSet two, fifty;
  two.curves.push_back({CurveKind::kCrossing, {Vec3(0, 0, 0), Vec3(1, 1, 0)}, false});
  fifty.curves.push_back({CurveKind::kCrossing, {}, false});
  for (int i = 0; i < 50; ++i) fifty.curves[0].points.push_back(Vec3(i / 49.0, i / 49.0, 0));
  EXPECT_EQ(singular_overlay_geometry(two, style, 1).vertex_count(),
            singular_overlay_geometry(fifty, style, 1).vertex_count());
  // Nothing to draw: nothing, and no batch.
  EXPECT_TRUE(singular_overlay_geometry({}, style, 1).batches.empty());
}

}  // namespace
}  // namespace zeroset::viewer
