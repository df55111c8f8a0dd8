// The `zeroset` command line as a user meets it: outputs, exit codes, error messages.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli/cli_support.h"
#include "zeroset/io/image.h"

namespace zeroset {
namespace {

using test::run_command;
using test::temp_dir;
using test::zs;

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

// ---- SURFER files -------------------------------------------------------------------------

std::string num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

const char* kSurferKummer =
    "(3-a)*(x^2+y^2+z^2-a)^2-(3*a-1)*(1-z-sqrt(2)*x)*(1-z+sqrt(2)*x)*(1+z+sqrt(2)*y)*"
    "(1+z-sqrt(2)*y)";

// SURFER's rotation_matrix (row by row, 4×4) for an orbit camera at azimuth, elevation and roll
// in degrees: its columns are the camera's right, up and back directions in the surface's
// coordinates (docs/scenes.md, "SURFER files").
std::string surfer_rotation(double az, double el, double roll) {
  const double a = az * M_PI / 180, e = el * M_PI / 180, r = roll * M_PI / 180;
  const double back[3] = {std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e)};
  // right0 = forward × z, up0 = right0 × forward, with forward = -back
  double right0[3] = {-back[1], back[0], 0};
  const double n = std::hypot(right0[0], right0[1]);
  for (double& v : right0) v /= n;
  const double up0[3] = {-(right0[1] * back[2]), right0[0] * back[2],
                         right0[1] * back[0] - right0[0] * back[1]};
  double m[3][3];
  for (int i = 0; i < 3; ++i) {
    m[i][0] = std::cos(r) * right0[i] + std::sin(r) * up0[i];
    m[i][1] = -std::sin(r) * right0[i] + std::cos(r) * up0[i];
    m[i][2] = back[i];
  }
  std::string out;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      out += num(i < 3 && j < 3 ? m[i][j] : (i == j ? 1.0 : 0.0)) + (i == 3 && j == 3 ? "" : " ");
  return out;
}

// A SURFER file with everything a hand or an old program may do: comments, a continued
// equation, a colon and a blank as separators, escapes, unknown keys, Windows line ends.
std::string surfer_file(double roll) {
  std::string text =
      "#SURFER file\n"
      "! saved by hand\n"
      "surface_name=Kummer \\u00e9\n"
      "surface_equation = (3-a)*(x^2+y^2+z^2-a)^2 \\\n"
      "      -(3*a-1)*(1-z-sqrt(2)*x)*(1-z+sqrt(2)*x)*(1+z+sqrt(2)*y)*(1+z-sqrt(2)*y)\n"
      "surface_parameter_a : 1.5\n"
      "surface_parameter_b  0.25\n"
      "scale_factor=0.3\n"
      "rotation_matrix=" +
      surfer_rotation(40, 25, roll) +
      "\n"
      "camera_type=PERSPECTIVE_CAMERA\n"
      "camera_fov_y=3\\\n  5\n"
      "camera_transform=1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0 -3.0 0.0 0.0 0.0 1.0\n"
      "background_color=0.2 0.4 0.6\n"
      "front_material_color=1.0 0.5 0.0\n"
      "back\\_material_color=0.1 0.3 0.2\n"
      "trace_patterns=false\n"
      "antialiasing_quality=high\n";
  std::string crlf;
  for (char c : text) crlf += c == '\n' ? std::string("\r\n") : std::string(1, c);
  return crlf;
}

std::string write_text(const std::string& name, const std::string& text) {
  const std::string path = temp_dir() + "/" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

TEST(CliJsurf, RendersWithItsParametersClipCameraAndColours) {
  const std::string dir = temp_dir();
  const std::string file = write_text("kummer.jsurf", surfer_file(15));
  const std::string look = " --size 96x96 --aa 1 -o ";
  auto r = run_command(zs("render " + file + look + dir + "/js.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // The same scene through zeroset's own options: radius 10^0.3, the camera 3 radii away.
  const double radius = std::pow(10.0, 0.3);
  const std::string same = "render \"" + std::string(kSurferKummer) +
                           "\" --param a=1.5 --clip sphere:" + num(radius) + " --camera 40,25," +
                           num(3 * radius) +
                           ",15 --fov 35 --background 0.2,0.4,0.6 --front 1,0.5,0 "
                           "--back 0.1,0.3,0.2";
  r = run_command(zs(same + look + dir + "/zs.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image a = read_image(dir + "/js.png"), b = read_image(dir + "/zs.png");
  EXPECT_TRUE(a.rgb == b.rgb) << "the .jsurf picture differs from zeroset's own";
  // The background is the file's colour, and the surface is in the picture.
  const std::uint8_t* corner = a.pixel(0, 0);
  EXPECT_EQ(corner[0], 51);
  EXPECT_EQ(corner[1], 102);
  EXPECT_EQ(corner[2], 153);
  size_t surface_pixels = 0;
  for (size_t i = 0; i < a.rgb.size(); i += 3)
    surface_pixels += a.rgb[i] != 51 || a.rgb[i + 1] != 102 || a.rgb[i + 2] != 153;
  EXPECT_GT(surface_pixels, a.rgb.size() / 3 / 10);
  // The roll is part of the rotation: without it the picture is another one.
  r = run_command(
      zs("render " + write_text("noroll.jsurf", surfer_file(0)) + look + dir + "/noroll.png"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_FALSE(read_image(dir + "/noroll.png").rgb == a.rgb);
}

TEST(CliJsurf, ExportedFileGivesTheSamePicture) {
  const std::string dir = temp_dir();
  const std::string file = write_text("round.jsurf", surfer_file(-20));
  auto r = run_command(zs("export " + file + " --format jsurf -o " + dir + "/again.jsurf"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const std::string& f : {file, dir + "/again.jsurf"}) {
    r = run_command(zs("render " + f + " --size 80x64 --aa 2 -o " + f + ".png"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
  const Image a = read_image(file + ".png"), b = read_image(dir + "/again.jsurf.png");
  EXPECT_TRUE(a.rgb == b.rgb) << "the exported file draws another picture";
  // And a catalog surface with another parameter name goes over as a..d.
  r = run_command(zs("export kummer --param mu=2 -o " + dir + "/k.jsurf"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir + "/k.jsurf");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("surface_parameter_a=2\n"), std::string::npos) << text;
  for (const std::string& f : {std::string("kummer --param mu=2"), dir + "/k.jsurf"}) {
    r = run_command(zs("render " + f + " --size 64x64 --aa 1 -o " + dir + "/k.png"));
    ASSERT_EQ(r.exit_code, 0) << r.output;
  }
}

TEST(CliJsurf, BadFilesExitWithCodeTwoNamingFileAndLine) {
  const std::string good = surfer_file(0);
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"scale_factor=zero\n", ":2: scale_factor"},
      {"rotation_matrix=2 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n", ":2: rotation_matrix"},
      {"camera_type=FISHEYE_CAMERA\n", ":2: camera_type"},
      {"camera_type=ORTHOGRAPHIC_CAMERA\ncamera_height=-2\n", ":3: camera_height"},
      {"front_material_color=0.5 0.5\n", ":2: front_material_color"},
  };
  for (const auto& [line, expected] : cases) {
    const std::string file = write_text("bad.jsurf", "surface_equation=x^2+y^2+z^2-1\n" + line);
    const auto r = run_command(zs("info " + file));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(file + expected), std::string::npos) << r.output;
  }
  const std::string file = write_text("none.jsurf", "# no equation\r\nscale_factor=1\r\n");
  const auto r = run_command(zs("render " + file + " -o " + temp_dir() + "/none.png"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("none.jsurf: no surface_equation"), std::string::npos) << r.output;
  const auto e =
      run_command(zs("export \"x^2+y^2-z^2\" --clip box:1 -o " + temp_dir() + "/c.jsurf"));
  EXPECT_EQ(e.exit_code, 2) << e.output;
  EXPECT_NE(e.output.find("one sphere"), std::string::npos) << e.output;
}

TEST(CliJsurf, EveryCommandTakesAJsurfSurface) {
  const std::string dir = temp_dir();
  const std::string f = write_text("every.jsurf", surfer_file(10));
  for (const std::string& cmd :
       {"info " + f, "eval " + f + " --at 0,0,0",
        "render " + f + " --size 48x48 -o " + dir + "/every.png",
        "sample " + f + " --seed 1 --steps 5 -o " + dir + "/every.ply",
        "mesh " + f + " -r 16 -o " + dir + "/every.obj",
        "export " + f + " -o " + dir + "/every.pov", "export " + f + " -o " + dir + "/every2.jsurf",
        "animate " + f + " --param a=1.4:1.6 --frames 2 --size 32x32 --no-video -o " + dir +
            "/every_frames"}) {
    const auto r = run_command(zs(cmd));
    EXPECT_EQ(r.exit_code, 0) << cmd << "\n" << r.output;
  }
}

TEST(CliRender, OrthographicProjectionFlag) {
  const std::string dir = temp_dir();
  auto r = run_command(
      zs("render sphere --projection ortho:3 --size 64x64 --aa 1 -o " + dir + "/o.png"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = run_command(zs("render sphere --projection ortho --size 64x64 --aa 1 -o " + dir + "/f.png"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* bad :
       {"fisheye", "ortho:-1", "ortho:nan", "ortho:1e300", "perspective:2", "ortho:"}) {
    r = run_command(zs(std::string("render sphere --projection ") + bad + " -o " + dir + "/b.png"));
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find("--projection"), std::string::npos) << bad << ": " << r.output;
  }
  // A SURFER file's orthographic camera, exported back as one.
  const std::string file =
      write_text("ortho.jsurf",
                 "#jSurfer\nsurface_equation=x^2+y^2+z^2-a^2\nsurface_parameter_a=0.5\n"
                 "camera_type=ORTHOGRAPHIC_CAMERA\ncamera_height=2.0\n");
  r = run_command(zs("render " + file + " --size 64x64 --aa 1 -o " + dir + "/j.png"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = run_command(zs("export " + file + " -o " + dir + "/j.pov"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir + "/j.pov");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("orthographic"), std::string::npos);
  r = run_command(zs("export " + file + " -o " + dir + "/j2.jsurf"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in2(dir + "/j2.jsurf");
  const std::string back((std::istreambuf_iterator<char>(in2)), std::istreambuf_iterator<char>());
  EXPECT_NE(back.find("camera_type=ORTHOGRAPHIC_CAMERA"), std::string::npos) << back;
  EXPECT_NE(back.find("camera_height=2\n"), std::string::npos) << back;
}

}  // namespace
}  // namespace zeroset
