// mesh_surface, the one recipe of every front end: its stages in order, what it tells its
// listeners, the step limit it keeps, its warnings and its statistics.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <stop_token>
#include <string>
#include <vector>

#include "mesh_test_support.h"
#include "zeroset/error.h"
#include "zeroset/mesh/mesh_surface.h"

namespace zeroset {
namespace {

MeshSettings cells(int n, Improver improver = Improver::kRemesh) {
  MeshSettings s;
  s.cells = n;
  s.improver = improver;
  return s;
}

TEST(MeshSurface, RunsTheStagesInOrderAndReportsEachOnce) {
  const Surface s = test::kummer(1.5);
  std::vector<std::string> events;
  MeshRun run;
  run.quality = true;
  run.on_polygonized = [&](const MeshResult& r) {
    events.push_back("polygonized");
    // The crossings have run, the improver not yet.
    EXPECT_TRUE(r.crossings.has_value());
    EXPECT_TRUE(r.singular.has_value());
    EXPECT_TRUE(r.quality_before.has_value());
    EXPECT_FALSE(r.improvement.has_value());
  };
  run.on_improver_step = [&](const MeshImprover&, int, bool) { events.push_back("step"); };
  const MeshResult r = mesh_surface(s, cells(24), run);
  // The remesher reports its result only; the paper's improver each step.
  ASSERT_EQ(events, std::vector<std::string>{"polygonized"});
  ASSERT_TRUE(r.improvement);
  EXPECT_EQ(r.improvement->improver, Improver::kRemesh);
  EXPECT_TRUE(r.improvement->summary().converged);
  ASSERT_TRUE(r.singular);
  EXPECT_EQ(r.singular->points_of(SingularPointKind::kNode).size(), 16u);
  EXPECT_EQ(r.improvement->remesh.singular_points.size(), 16u);
  EXPECT_FALSE(r.stopped);
  EXPECT_TRUE(r.warnings.empty());
  EXPECT_TRUE(r.topology_after->is_watertight() || r.topology_after->boundary_edges > 0);
  EXPECT_EQ(r.quality_after->triangles, r.mesh.triangle_count());
}

TEST(MeshSurface, ThePapersImproverReportsEveryStepAndKeepsTheLimit) {
  const Surface s = test::kummer(1.5);
  MeshSettings settings = cells(16, Improver::kPaper);
  settings.max_improve_steps = 7;
  std::vector<int> steps;
  int done = 0;
  MeshRun run;
  run.on_improver_step = [&](const MeshImprover&, int k, bool is_done) {
    steps.push_back(k);
    done += is_done;
  };
  const MeshResult r = mesh_surface(s, settings, run);
  ASSERT_TRUE(r.improvement);
  EXPECT_EQ(steps, (std::vector<int>{1, 2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(done, 1);
  EXPECT_EQ(r.improvement->paper.steps, 7);
  // Improving a mesh further counts the steps already taken against the same limit.
  Mesh mesh = r.mesh;
  steps.clear();
  const auto more = improve_surface_mesh(mesh, s, settings, run, nullptr, 5);
  ASSERT_TRUE(more);
  EXPECT_EQ(steps, (std::vector<int>{6, 7}));
  EXPECT_FALSE(improve_surface_mesh(mesh, s, settings, run, nullptr, 7));
}

TEST(MeshSurface, StatisticsHoldEveryStageAndTheImproversOwnKeys) {
  const Surface s = test::kummer(3);
  MeshRun run;
  run.quality = true;
  const nlohmann::json remeshed = mesh_surface(s, cells(20), run).to_json();
  for (const char* key : {"surface", "parameters", "clip", "field", "polygonize", "singular_set",
                          "crossings", "quality_before", "topology_before", "improve",
                          "quality_after", "topology_after", "seconds_total"})
    EXPECT_TRUE(remeshed.contains(key)) << key;
  EXPECT_EQ(remeshed["improve"]["improver"], "remesh");
  EXPECT_TRUE(remeshed["improve"].contains("iterations"));
  EXPECT_GT(remeshed["crossings"]["crossing_curves"].get<int>(), 0);
  MeshSettings paper = cells(12, Improver::kPaper);
  paper.max_improve_steps = 3;
  const nlohmann::json improved = mesh_surface(s, paper).to_json();
  EXPECT_EQ(improved["improve"]["improver"], "paper");
  EXPECT_EQ(improved["improve"]["steps"], 3);
  EXPECT_FALSE(improved.contains("quality_after"));  // measured on request only
  // No improvement, no "improve".
  MeshSettings off = cells(12);
  off.improve = false;
  EXPECT_FALSE(mesh_surface(s, off).to_json().contains("improve"));
}

TEST(MeshSurface, WarningsGoToTheListenerAsTheyArise) {
  const Surface s = test::equation("log(x) + y", Clip::sphere(1));
  std::vector<std::string> heard;
  MeshRun run;
  run.on_warning = [&](const std::string& line) { heard.push_back(line); };
  const MeshResult r = mesh_surface(s, cells(12), run);
  ASSERT_FALSE(heard.empty());
  EXPECT_EQ(heard, r.warnings);
  EXPECT_NE(heard.front().find("F is undefined"), std::string::npos) << heard.front();
}

TEST(MeshSurface, BadSettingsAndAStopEndTheRunCleanly) {
  const Surface s = test::kummer(1.5);
  EXPECT_THROW(mesh_surface(s, cells(0)), SettingError);
  std::stop_source stop;
  MeshRun run;
  run.on_polygonized = [&](const MeshResult&) { stop.request_stop(); };
  const MeshResult r = mesh_surface(s, cells(16), run, stop.get_token());
  EXPECT_TRUE(r.stopped);
  EXPECT_FALSE(r.improvement);
}

}  // namespace
}  // namespace zeroset
