#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "support/run_command.h"
#include "zeroset/io/ply.h"
#include "zeroset/mesh/adjacency.h"
#include "zeroset/mesh/mesh_io.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;

class MeshCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("zeroset_mesh_cli_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  test::CommandResult run(const std::string& args) const {
    return test::run_command(std::string(ZEROSET_BINARY) + " --quiet mesh " + args);
  }
  fs::path dir_;
};

TEST_F(MeshCli, WritesMeshAndStats) {
  const auto r = run("sphere --resolution 16 -o " + path("s.ply") + " --stats " + path("s.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Mesh m = read_mesh(path("s.ply"));
  EXPECT_TRUE(mesh_topology(m).is_watertight());
  std::ifstream in(path("s.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["quality_after"]["triangles"].get<size_t>(), m.triangle_count());
  EXPECT_TRUE(j.contains("quality_before"));
  EXPECT_TRUE(j["topology_after"]["watertight"].get<bool>());
}

TEST_F(MeshCli, ReadsTheMeshSettingsTheViewerSaves) {
  // The viewer writes {"cells": N, "improve": true|false}; flags given explicitly win.
  std::ofstream(path("scene.json"))
      << R"({"name": "sphere", "mesh": {"cells": 12, "improve": true}})";
  auto stats = [&](const std::string& flags) {
    const auto r = run(path("scene.json") + " " + flags + " -o " + path("s.ply") + " --stats " +
                       path("s.json"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(path("s.json"));
    return nlohmann::json::parse(in);
  };
  // true: until at rest, not 1 step; by the remesher (the default) or the improver given.
  const nlohmann::json improved = stats("");
  EXPECT_EQ(improved["polygonize"]["resolution"].get<int>(), 12);
  ASSERT_TRUE(improved.contains("improve")) << improved.dump();
  EXPECT_EQ(improved["improve"]["improver"], "remesh");
  EXPECT_GT(improved["improve"]["iterations"].get<int>(), 1);
  EXPECT_TRUE(improved["improve"]["converged"].get<bool>());
  const nlohmann::json paper = stats("--improver paper");
  EXPECT_EQ(paper["improve"]["improver"], "paper");
  EXPECT_GT(paper["improve"]["steps"].get<int>(), 1);
  EXPECT_TRUE(paper["improve"]["converged"].get<bool>());
  const nlohmann::json flagged = stats("--resolution 10 --improve off");
  EXPECT_EQ(flagged["polygonize"]["resolution"].get<int>(), 10);
  EXPECT_FALSE(flagged.contains("improve"));
}

TEST_F(MeshCli, RemeshesWithTheImproverFlagOrTheSceneKey) {
  auto improve = [&](const std::string& args) {
    const auto r = run(args + " -o " + path("k.ply") + " --stats " + path("k.json"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(path("k.json"));
    return nlohmann::json::parse(in);
  };
  const nlohmann::json j = improve("kummer --param mu=1.5 --resolution 24 --improver remesh");
  const nlohmann::json& imp = j["improve"];
  EXPECT_EQ(imp["improver"], "remesh");
  EXPECT_TRUE(imp["converged"].get<bool>());
  EXPECT_GT(imp["splits"].get<long long>(), 0);
  EXPECT_GT(imp["collapses"].get<long long>(), 0);
  EXPECT_GT(imp["flips"].get<long long>(), 0);
  EXPECT_GT(imp["iterations"].get<int>(), 0);
  EXPECT_GT(imp["seconds"].get<double>(), 0);
  EXPECT_GT(j["quality_after"]["mean_min_angle_deg"].get<double>(),
            j["quality_before"]["mean_min_angle_deg"].get<double>());
  EXPECT_EQ(j["quality_after"]["zero_area_triangles"].get<size_t>(), 0u);
  // The scene file's key, and the flag winning over it.
  std::ofstream(path("scene.json"))
      << R"({"name": "sphere", "mesh": {"cells": 12, "improver": "remesh"}})";
  EXPECT_EQ(improve(path("scene.json"))["improve"]["improver"], "remesh");
  EXPECT_EQ(improve(path("scene.json") + " --improver paper")["improve"]["improver"], "paper");
  std::ofstream(path("bad.json"))
      << R"({"name": "sphere", "mesh": {"cells": 12, "improver": "springs"}})";
  const auto r = run(path("bad.json") + " -o " + path("b.obj"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/mesh/improver"), std::string::npos) << r.output;
}

TEST_F(MeshCli, RefineStepsZeroIsLinearInterpolationOffTheSurface) {
  // Linear interpolation leaves the vertices of a sphere inside it, off F = 0 by about h²;
  // the default refinement puts them on it to rounding.
  auto max_residual = [&](const std::string& flags) {
    const auto r = run("sphere --resolution 16 --improve off " + flags + " -o " + path("s.ply") +
                       " --stats " + path("s.json"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    std::ifstream in(path("s.json"));
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["polygonize"]["refine_evaluations"].get<long long>() == 0,
              flags.find("--refine-steps 0") != std::string::npos);
    return j["quality_before"]["residual"]["max"].get<double>();
  };
  EXPECT_GT(max_residual("--refine-steps 0"), 1e-4);
  EXPECT_LT(max_residual(""), 1e-12);
}

TEST_F(MeshCli, BadInputExitsWithTwoAndWritesNothing) {
  for (const std::string& args :
       {std::string("sphere --resolution 0 -o ") + path("a.obj"),
        std::string("sphere --resolution 30000 -o ") + path("a.obj"),
        std::string("sphere -o ") + path("a.xyz"), std::string("sphere -o ") + path("nodir/a.obj"),
        std::string("sphere --improve sometimes -o ") + path("a.obj"),
        std::string("sphere --boundary loose -o ") + path("a.obj"),
        std::string("sphere --improver cgal -o ") + path("a.obj"),
        std::string("sphere --refine-steps -1 -o ") + path("a.obj")}) {
    const auto r = run(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("error"), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(path("a.obj")));
  EXPECT_FALSE(fs::exists(path("a.xyz")));
}

TEST_F(MeshCli, ThePaperImproversOwnFlagsAreRefusedWithTheRemesher) {
  // They would do nothing there; a scene file's keys are kept (they wait for --improver
  // paper), an explicit flag is refused whether the remesher is the default or the scene's.
  std::ofstream(path("scene.json"))
      << R"({"name": "sphere", "mesh": {"cells": 10, "improver": "remesh", "flips": false}})";
  for (const std::string flag :
       {"--no-curvature", "--curvature-weight 3", "--no-singularity", "--no-flips"}) {
    for (const std::string& surface : {std::string("sphere -r 10"), path("scene.json")}) {
      const auto r = run(surface + " " + flag + " -o " + path("a.obj"));
      EXPECT_EQ(r.exit_code, 2) << flag << "\n" << r.output;
      const std::string name = flag.substr(0, flag.find(' '));
      EXPECT_NE(r.output.find(name + " sets the paper's improver"), std::string::npos) << r.output;
      EXPECT_NE(r.output.find("add --improver paper"), std::string::npos) << r.output;
      EXPECT_FALSE(fs::exists(path("a.obj")));
      EXPECT_EQ(run(surface + " --improver paper " + flag + " -o " + path("a.obj")).exit_code, 0)
          << flag;
      fs::remove(path("a.obj"));
    }
  }
  EXPECT_EQ(run(path("scene.json") + " -o " + path("a.obj")).exit_code, 0);
  // --help says which flags are the paper improver's.
  const std::string help = run("--help").output;
  const size_t group = help.find("Paper improver only (--improver paper)");
  ASSERT_NE(group, std::string::npos) << help;
  for (const char* text : {"Springs without the curvature estimator", "kappa_d, the weight",
                           "Springs without the singularity estimator", "No Delaunay edge flips"})
    EXPECT_GT(help.find(text), group) << text;
}

TEST_F(MeshCli, AbsurdResolutionIsRefusedWithTheMemoryItNeeds) {
  const auto r = run("kummer --resolution 30000 -o " + path("k.obj"));
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("GB"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(path("k.obj")));
  // The message names the resolution asked for and a smaller one that fits.
  EXPECT_NE(r.output.find("--resolution = 30000:"), std::string::npos) << r.output;
  const std::string use = "use --resolution ";
  const size_t at = r.output.find(use);
  ASSERT_NE(at, std::string::npos) << r.output;
  const int fits = std::stoi(r.output.substr(at + use.size()));
  EXPECT_GT(fits, 0);
  EXPECT_LT(fits, 30000);
}

// Whitney's umbrella: its crossing half-line and its handle (an isolated real curve) are in
// the mesh files as polylines, OBJ 'l' lines and PLY edges, unless --no-curves; the files
// still load as triangle meshes.
TEST_F(MeshCli, WritesSingularCurvesAsPolylinesUnlessNoCurves) {
  auto r = run("whitney -r 24 -o " + path("w.obj") + " --stats " + path("w.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream obj(path("w.obj"));
  std::string line, previous;
  int crossing = 0, isolated = 0;
  while (std::getline(obj, line)) {
    if (line.rfind("l ", 0) == 0) {
      crossing += previous == "# crossing curve";
      isolated += previous == "# isolated curve";
    }
    previous = line;
  }
  EXPECT_EQ(crossing, 1);
  EXPECT_EQ(isolated, 1);
  const Mesh m = read_mesh(path("w.obj"));
  EXPECT_GT(m.triangle_count(), 100u);
  std::ifstream in(path("w.json"));
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["crossings"]["crossing_curves"].get<int>(), 1);
  EXPECT_EQ(j["crossings"]["failure"].get<std::string>(), "");
  // Edges of the crossing curve carry four triangles: the mesh is not a 2-manifold there.
  EXPECT_GT(j["topology_after"]["non_manifold_edges"].get<int>(), 0);

  ASSERT_EQ(run("whitney -r 24 -o " + path("w.ply")).exit_code, 0);
  const PlyData ply = read_ply(path("w.ply"));
  EXPECT_GT(ply.edges.size(), 10u);
  EXPECT_EQ(read_mesh(path("w.ply")).triangle_count(), m.triangle_count());

  ASSERT_EQ(run("whitney -r 24 --no-curves -o " + path("n.ply")).exit_code, 0);
  EXPECT_TRUE(read_ply(path("n.ply")).edges.empty());
  ASSERT_EQ(run("whitney -r 24 --no-crossings --stats " + path("n.json")).exit_code, 0);
  std::ifstream n(path("n.json"));
  EXPECT_FALSE(nlohmann::json::parse(n).contains("crossings"));
}

}  // namespace
}  // namespace zeroset
