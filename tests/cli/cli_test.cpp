// The `zeroset` command line as a user meets it: outputs, exit codes, error messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "support/run_command.h"
#include "zeroset/io/image.h"

namespace zeroset {
namespace {

using test::run_command;

std::string zs(const std::string& args) { return std::string(ZEROSET_BINARY) + " " + args; }

std::string temp_dir() {
  auto d = std::filesystem::temp_directory_path() / "zeroset_cli_test";
  std::filesystem::create_directories(d);
  return d.string();
}

TEST(Cli, ListShowsEveryCatalogSurfaceOnOneLineEach) {
  const auto r = run_command(zs("list"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* name : {"kummer", "cone", "planes", "roman", "barth6", "cayley"})
    EXPECT_NE(r.output.find(name), std::string::npos) << name;
}

TEST(Cli, HelpTeachesWithExamples) {
  const auto r = run_command(zs("--help"));
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("Examples"), std::string::npos);
  EXPECT_NE(r.output.find("Exit codes"), std::string::npos);
}

TEST(Cli, EvalAtAKummerNodeGivesZeroValueAndGradient) {
  const auto r =
      run_command(zs("eval kummer --param mu=1.5 --at 1.0606601718,-0.3535533906,-0.5 --json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(r.output);
  EXPECT_LE(std::abs(j.at("value").get<double>()), 1e-8) << r.output;
  ASSERT_EQ(j.at("gradient").size(), 3u) << r.output;
  for (const auto& g : j.at("gradient")) EXPECT_LE(std::abs(g.get<double>()), 1e-8) << r.output;
}

TEST(Cli, EvalPrintsValueGradientAndHessian) {
  const auto r = run_command(zs("eval \"x^2 + y^2 - z^2\" --at 1,2,3"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("F         -4"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Hessian"), std::string::npos) << r.output;
}

TEST(Cli, InfoListsSingularPoints) {
  const auto r = run_command(zs("info kummer --param mu=1.5"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("16 known"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("degree:     4"), std::string::npos) << r.output;
}

TEST(Cli, InfoListsTheSingularSetFound) {
  const auto r = run_command(zs("info roman"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3 crossing curves, 6 isolated curves; 1 triple point, 6 pinch points"),
            std::string::npos)
      << r.output;
  const auto j = run_command(zs("info whitney --json"));
  ASSERT_EQ(j.exit_code, 0) << j.output;
  const auto set = nlohmann::json::parse(j.output)["singular_set"];
  EXPECT_EQ(set["curves"].size(), 2u);
  EXPECT_FALSE(set["singular_sheet"].get<bool>());
}

TEST(Cli, ASingularSheetIsReportedByInfoAndWarnedAboutByMeshAndSample) {
  const std::string k = "kummer --param mu=0.3333333333333333";
  const auto info = run_command(zs("info " + k));
  ASSERT_EQ(info.exit_code, 0) << info.output;
  EXPECT_NE(info.output.find("grad F vanishes on a whole sheet"), std::string::npos) << info.output;
  const std::string dir = temp_dir();
  for (const std::string& cmd : {"mesh " + k + " -r 32 -o " + dir + "/sheet.obj",
                                 "sample " + k + " --steps 60 -o " + dir + "/sheet.ply"}) {
    const auto r = run_command(zs(cmd));
    EXPECT_EQ(r.exit_code, 0) << cmd << ": " << r.output;
    EXPECT_NE(r.output.find("grad F vanishes on a whole sheet of F = 0"), std::string::npos)
        << cmd << ": " << r.output;
  }
}

TEST(Cli, MalformedEquationExitsTwoWithColumnAndCaret) {
  const auto r = run_command(zs("info \"x^2 + \""));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("column"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find('^'), std::string::npos) << r.output;
}

TEST(Cli, MissingParametersAreAllNamed) {
  const auto r = run_command(zs("eval \"a*x + b*y + c\" --at 0,0,0"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  for (const char* p : {"a", "b", "c"})
    EXPECT_NE(r.output.find(std::string(" ") + p), std::string::npos) << r.output;
}

TEST(Cli, BadInputsExitTwoWithAMessage) {
  for (const char* args :
       {"eval kummer --at 1,2", "eval kummer --at 1,2,nan", "eval kummer --param mu=abc --at 0,0,0",
        "eval kummer --param nu=1 --at 0,0,0", "info kummer --clip sphere:-1", "info kumer",
        "info no_such_file.json", "eval sphere", "frobnicate", "info \"sin(x\""}) {
    const auto r = run_command(zs(args));
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_FALSE(r.output.empty()) << args;
    EXPECT_EQ(r.output.find("terminate"), std::string::npos) << args << r.output;
  }
}

TEST(Cli, InfoReadsASceneFile) {
  const std::string path = temp_dir() + "/scene.json";
  {
    FILE* f = std::fopen(path.c_str(), "w");
    std::fputs(R"({"equation": "x^2 + y^2 - a", "parameters": {"a": 2}, "clip": ["sphere:2"]})", f);
    std::fclose(f);
  }
  const auto r = run_command(zs("info " + path));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("a = 2"), std::string::npos) << r.output;
}

TEST(Cli, RenderWritesTheSamePictureAsPngAndAsPpm) {
  const std::string png = temp_dir() + "/cone.png", ppm = temp_dir() + "/cone.ppm";
  for (const std::string& out : {png, ppm}) {
    const auto r = run_command(zs("-q render cone --size 64x48 --aa 1 -o " + out));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const Image a = read_image(png), b = read_image(ppm);
  EXPECT_EQ(a.width, 64);
  EXPECT_EQ(a.height, 48);
  EXPECT_EQ(b.width, 64);
  EXPECT_EQ(b.height, 48);
  EXPECT_EQ(a.rgb, b.rgb);
  // The cone is drawn: some pixels differ from the white background.
  EXPECT_NE(std::count(a.rgb.begin(), a.rgb.end(), 255), static_cast<long>(a.rgb.size()));
}

TEST(Cli, RenderRejectsAnUnknownPictureFormatBeforeWritingAnything) {
  const std::string out = temp_dir() + "/cone.jpg";
  std::filesystem::remove(out);
  const auto r = run_command(zs("render cone --size 64x48 -o " + out));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(".ppm"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST(Cli, ShowSingularDrawsTheSetOverRenderMeshAndSamplePictures) {
  const std::string d = temp_dir();
  const std::vector<std::pair<std::string, std::string>> commands = {
      {"render", "render whitney --size 97x97 --aa 1 -o "},
      {"mesh", "mesh whitney -r 16 --size 97x97 --png "},
      {"sample", "sample whitney --seed 1 --steps 20 --size 97x97 --png "}};
  for (const auto& [name, args] : commands) {
    const std::string plain = d + "/" + name + "-plain.png", drawn = d + "/" + name + "-set.png";
    auto r = run_command(zs("-q " + args + plain));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    r = run_command(zs("-q " + args + drawn + " --show-singular"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    // The handle below the umbrella is drawn in magenta (isolated curves). The picture
    // itself may show it too where a ray passes exactly through the axis.
    const Image a = read_image(plain), b = read_image(drawn);
    auto is_magenta = [](const Image& img, size_t i) {
      return img.rgb[i + 1] + 30 < img.rgb[i] && img.rgb[i + 1] + 30 < img.rgb[i + 2];
    };
    int magenta = 0;
    for (size_t i = 0; i + 2 < a.rgb.size(); i += 3)
      magenta += !is_magenta(a, i) && is_magenta(b, i);
    EXPECT_GT(magenta, 5) << name;
  }
  const auto help = run_command(zs("render --help"));
  EXPECT_NE(help.output.find("--show-singular"), std::string::npos);
  EXPECT_NE(help.output.find("magenta"), std::string::npos);
}

TEST(Cli, StatsOfRenderMeshAndSampleListTheSingularSet) {
  const std::string d = temp_dir();
  for (const std::string& args :
       {std::string("render roman --size 32x32 --aa 1 -o ") + d + "/s.png --stats ",
        std::string("mesh roman -r 16 --stats "),
        std::string("sample roman --seed 1 --steps 10 --stats ")}) {
    const std::string stats = d + "/stats.json";
    std::filesystem::remove(stats);
    const auto r = run_command(zs("-q " + args + stats));
    ASSERT_EQ(r.exit_code, 0) << args << r.output;
    std::ifstream in(stats);
    const nlohmann::json j = nlohmann::json::parse(in);
    ASSERT_TRUE(j.contains("singular_set")) << args;
    const auto& set = j.at("singular_set");
    EXPECT_EQ(set.at("curves").size(), 9u) << args << ": 3 crossing, 6 isolated";
    int triple = 0;
    for (const auto& p : set.at("points")) triple += p.at("kind") == "triple";
    EXPECT_EQ(triple, 1) << args;
  }
}

}  // namespace
}  // namespace zeroset
