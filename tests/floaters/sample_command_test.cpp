// `zeroset sample`: outputs, animation, and bad input (exit code 2, no partial files).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "support/run_command.h"
#include "zeroset/floaters/ply.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;

class SampleCommand : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("zeroset_sample_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static test::CommandResult run(const std::string& args) {
    return test::run_command(std::string(ZEROSET_BINARY) + " " + args);
  }
  bool empty_dir() const { return fs::is_empty(dir_); }

  fs::path dir_;
};

TEST_F(SampleCommand, WritesPointsPictureAndStatistics) {
  const auto r = run("sample sphere --max-count 300 --seed 3 -o " + path("s.ply") + " --png " +
                     path("s.png") + " --size 120x100 --stats " + path("s.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const PointSet ps = read_points_ply(path("s.ply"));
  EXPECT_GT(ps.positions.size(), 50u);
  EXPECT_EQ(ps.normals.size(), ps.positions.size());
  EXPECT_EQ(ps.radii.size(), ps.positions.size());
  EXPECT_TRUE(fs::file_size(path("s.png")) > 0);
  std::ifstream in(path("s.json"));
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["metrics"]["count"].get<std::size_t>(), ps.positions.size());
  EXPECT_LT(j["metrics"]["residual"]["median"].get<double>(), 1e-6);
  EXPECT_TRUE(j["converged_at_step"].is_number());
  EXPECT_GT(j["updates_per_second"].get<double>(), 0);
  EXPECT_EQ(j["options"]["radius_adapt"], "mixed");
}

TEST_F(SampleCommand, AnimationReportsTheWorstResidual) {
  const auto r = run("sample kummer --max-count 300 --animate mu=1.02:1.3 --steps 100 --stats " +
                     path("a.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(path("a.json"));
  const auto j = nlohmann::json::parse(in);
  EXPECT_LE(j["animation"]["median_residual_worst"].get<double>(), 1e-3);
  EXPECT_DOUBLE_EQ(j["parameters"]["mu"].get<double>(), 1.3);
}

TEST_F(SampleCommand, ExtensionsCanBeSwitchedOff) {
  const auto r =
      run("sample planes --max-count 200 --steps 20 --no-cos-weight --no-snap "
          "--no-clip-projection --plain-repulsion --grading 0 --radius-adapt wh "
          "--no-clip-newton --no-average-mu --no-local-radius --no-taper --no-fission-offset "
          "--feedback 20 --equilibrium-speed 3 --estimator-interval 5 --ascii -o " +
          path("p.ply") + " --stats " + path("p.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(path("p.json"));
  const auto o = nlohmann::json::parse(in)["options"];
  EXPECT_FALSE(o["cos_weight"].get<bool>());
  EXPECT_FALSE(o["snap_to_nodes"].get<bool>());
  EXPECT_FALSE(o["clip_projection"].get<bool>());
  EXPECT_FALSE(o["scaled_repulsion"].get<bool>());
  EXPECT_EQ(o["radius_adapt"], "wh");
  for (const char* key : {"clip_newton", "average_radius_factor", "local_nominal_radius",
                          "energy_taper", "fission_offset"})
    EXPECT_FALSE(o[key].get<bool>()) << key;
  EXPECT_EQ(o["feedback"], 20);
  EXPECT_EQ(o["equilibrium_speed"], 3);
  EXPECT_EQ(o["estimator_interval"], 5);
}

TEST_F(SampleCommand, ReadsFloaterSettingsFromASceneFile) {
  {
    std::ofstream out(path("scene.json"));
    out << R"({"zeroset_scene": 1, "name": "kummer", "parameters": {"mu": {"value": 2.0}},
               "floaters": {"max_count": 400, "seed": 5, "radius_adapt": "wh"}})";
  }
  const auto r =
      run("sample " + path("scene.json") + " --steps 5 --seed 6 --stats " + path("s.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(path("s.json"));
  const auto j = nlohmann::json::parse(in);
  EXPECT_EQ(j["options"]["max_count"], 400);
  EXPECT_EQ(j["options"]["radius_adapt"], "wh");
  EXPECT_EQ(j["options"]["seed"], 6);  // the flag wins
  EXPECT_DOUBLE_EQ(j["parameters"]["mu"].get<double>(), 2.0);
}

TEST_F(SampleCommand, BadInputExitsWithTwoAndWritesNothing) {
  const std::string out = " -o " + path("x.ply") + " --png " + path("x.png");
  // Each case with a piece of the message that must name the problem.
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"sample kummer --radius -1" + out, "--radius"},
      {"sample kummer --radius nan" + out, "--radius"},
      {"sample kummer --max-count 0" + out, "--max-count"},
      {"sample kummer --radius-adapt fast" + out, "--radius-adapt"},
      {"sample kummer --feedback 70" + out, "--feedback"},
      {"sample kummer --feedback -1" + out, "--feedback"},
      {"sample kummer --feedback nan" + out, "--feedback"},
      {"sample kummer --equilibrium-speed 0" + out, "--equilibrium-speed"},
      {"sample kummer --equilibrium-speed 20" + out, "--equilibrium-speed"},
      {"sample kummer --estimator-interval 0" + out, "--estimator-interval"},
      {"sample kummer --estimator-interval 5000" + out, "--estimator-interval"},
      {"sample kummer --estimator-interval 2.5" + out, "--estimator-interval"},
      {"sample kummer --no-taper=maybe" + out, "--no-taper"},
      {"sample kummer --steps 5 --until-converged" + out, "--until-converged"},
      {"sample kummer --animate mu=1:2" + out, "--steps"},
      {"sample kummer --animate nu=1:2 --steps 5" + out, "nu"},
      {"sample kummer --animate mu=1 --steps 5" + out, "--animate"},
      {"sample kummer --camera 0,100" + out, "elevation"},
      {"sample kummer -o " + path("x.txt"), ".ply"},
      {"sample kummer --png " + path("x.jpg"), ".png"},
      {"sample kummer", "nothing to write"},
      {"sample \"x^2 +\"" + out, "column 5"},
      {"sample \"x*y - 1\"" + out, "clip"},
      {"sample kummer -o " + path("no/such/dir/x.ply"), "no/such/dir"},
  };
  {
    std::ofstream out(path("bad.json"));
    out << R"({"name": "kummer", "floaters": {"max_count": "many"}})";
  }
  const auto bad_scene = run("sample " + path("bad.json") + out);
  EXPECT_EQ(bad_scene.exit_code, 2);
  EXPECT_NE(bad_scene.output.find("/floaters/max_count"), std::string::npos) << bad_scene.output;
  fs::remove(path("bad.json"));
  for (const char* entry :
       {R"("feedback": 100)", R"("equilibrium_speed": -1)", R"("estimator_interval": 0)",
        R"("energy_taper": "off")", R"("clip_newton": 0)"}) {
    {
      std::ofstream scene(path("bad.json"));
      scene << R"({"name": "kummer", "floaters": {)" << entry << "}}";
    }
    const auto r = run("sample " + path("bad.json") + out);
    EXPECT_EQ(r.exit_code, 2) << entry << "\n" << r.output;
    const std::string key = std::string(entry).substr(1, std::string(entry).find('"', 1) - 1);
    EXPECT_NE(r.output.find("/floaters/" + key), std::string::npos) << r.output;
    fs::remove(path("bad.json"));
  }
  for (const auto& [args, expected] : cases) {
    const auto r = run(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << args << "\n" << r.output;
    EXPECT_TRUE(empty_dir()) << args;
  }
}

TEST_F(SampleCommand, RadiusOutsideItsRangeIsKeptInsideAndSaidSo) {
  const auto tiny = run("sample kummer --radius 1e-300 --steps 2 -o " + path("t.ply"));
  EXPECT_EQ(tiny.exit_code, 0) << tiny.output;
  EXPECT_NE(tiny.output.find("warning: radius 1e-300 is outside"), std::string::npos)
      << tiny.output;
  EXPECT_NE(tiny.output.find("using 3e-09"), std::string::npos) << tiny.output;
  const auto fine = run("sample kummer --radius 0.1 --steps 2 -o " + path("f.ply"));
  EXPECT_EQ(fine.exit_code, 0) << fine.output;
  EXPECT_EQ(fine.output.find("is outside"), std::string::npos) << fine.output;
}

TEST_F(SampleCommand, FloatersThatFindNoSurfaceAreReported) {
  // F ≥ 1 everywhere: floaters gather at the minimum of F, off any surface.
  const auto none =
      run("sample \"x^2 + y^2 + z^2 + 1\" --clip sphere:1 --max-count 100 "
          "--steps 300 -o " +
          path("n.ply"));
  EXPECT_EQ(none.exit_code, 0) << none.output;
  EXPECT_NE(none.output.find("warning"), std::string::npos) << none.output;
  EXPECT_NE(none.output.find("not on F = 0"), std::string::npos) << none.output;
  // F undefined everywhere: every floater is removed.
  const auto nan = run("sample \"sqrt(-1) + x\" --clip sphere:1 --steps 20 -o " + path("u.ply"));
  EXPECT_EQ(nan.exit_code, 0) << nan.output;
  EXPECT_NE(nan.output.find("no floater stayed"), std::string::npos) << nan.output;
  // A settled sampling of a real surface says nothing of the kind.
  const auto kummer = run("sample kummer --max-count 400 -o " + path("k.ply"));
  EXPECT_EQ(kummer.exit_code, 0) << kummer.output;
  EXPECT_EQ(kummer.output.find("warning"), std::string::npos) << kummer.output;
}

}  // namespace
}  // namespace zeroset
