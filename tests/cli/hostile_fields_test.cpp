// Fields that are undefined (NaN or infinite) on part of the clip, that vanish identically or
// whose first-order distance misleads, through the built `zeroset`: exit codes, warnings, and
// written files whose every number is finite, every vertex inside the clip and where F is
// finite, and no wall at a pole.
#include <gtest/gtest.h>

#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "cli/cli_support.h"
#include "zeroset/types.h"

namespace zeroset::test {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Whether the text holds a word that a writer makes of a non-finite double ("nan", "-inf",
// "inf," in a list, "<nan," in a vector...).
bool has_non_finite_word(const std::string& text) {
  std::string spaced;
  for (char c : text)
    spaced += std::string("<>,(){}:;[]\"=").find(c) != std::string::npos
                  ? ' '
                  : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  std::istringstream in(spaced);
  std::string w;
  while (in >> w) {
    if (!w.empty() && (w[0] == '-' || w[0] == '+')) w.erase(0, 1);
    if (w == "nan" || w == "inf" || w == "infinity" || w == "nan(ind)") return true;
  }
  return false;
}

// The vertices of an OBJ file ("v x y z" lines).
std::vector<Vec3> obj_vertices(const std::string& path) {
  std::vector<Vec3> out;
  std::istringstream in(read_text(path));
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) != 0) continue;
    std::istringstream l(line.substr(2));
    Vec3 p;
    l >> p.x() >> p.y() >> p.z();
    out.push_back(p);
  }
  return out;
}

// The points of an ASCII PLY file (first three numbers of each vertex line).
std::vector<Vec3> ply_points(const std::string& path) {
  std::istringstream in(read_text(path));
  std::string line;
  long long count = 0;
  while (std::getline(in, line) && line != "end_header")
    if (line.rfind("element vertex ", 0) == 0) count = std::stoll(line.substr(15));
  std::vector<Vec3> out;
  for (long long n = 0; n < count && std::getline(in, line); ++n) {
    std::istringstream l(line);
    Vec3 p;
    l >> p.x() >> p.y() >> p.z();
    out.push_back(p);
  }
  return out;
}

struct MeshCase {
  std::string equation;
  double clip_radius;
  std::function<bool(const Vec3&)> defined;  // F finite at p
  bool undefined_somewhere;                  // the warning names a fraction of the clip
};

// Meshes each field and checks the file: finite numbers, vertices in the clip where F is
// finite, and the warning where F is undefined on part of the clip.
TEST(HostileFields, MeshesKeepEveryVertexInsideTheClipWhereFIsFinite) {
  const std::string dir = fresh_dir("hostile_mesh");
  const std::vector<MeshCase> cases = {
      {"sqrt(x) + y^2 + z^2 - 1", 2, [](const Vec3& p) { return p.x() >= 0; }, true},
      {"log(x) + y^2 + z^2", 2, [](const Vec3& p) { return p.x() > 0; }, true},
      {"sqrt(1 - x^2 - y^2 - z^2) + z", 1.5,
       [](const Vec3& p) { return p.squaredNorm() <= 1 + 1e-12; }, true},
      {"1/x - 1", 2, [](const Vec3& p) { return p.x() != 0; }, false},
      {"tan(x) - y", 3, [](const Vec3&) { return true; }, false},
  };
  for (const MeshCase& c : cases) {
    SCOPED_TRACE(c.equation);
    const std::string obj = dir + "/m.obj", stats = dir + "/m.json";
    std::filesystem::remove(obj);
    const auto r =
        run_command(zs("mesh '" + c.equation + "' --clip sphere:" + std::to_string(c.clip_radius) +
                       " -r 40 --improve 40 -o " + obj + " --stats " + stats));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output.find("F is undefined") != std::string::npos, c.undefined_somewhere)
        << r.output;
    EXPECT_EQ(r.output.find("vertices lie where F is undefined"), std::string::npos) << r.output;
    EXPECT_FALSE(has_non_finite_word(read_text(obj)));
    const std::vector<Vec3> v = obj_vertices(obj);
    ASSERT_FALSE(v.empty());
    for (const Vec3& p : v) {
      ASSERT_LE(p.norm(), c.clip_radius * (1 + 1e-9)) << p.transpose();
      ASSERT_TRUE(c.defined(p)) << p.transpose();
    }
    const auto j = nlohmann::json::parse(read_text(stats));
    EXPECT_EQ(j["improve"]["undefined_vertices"], 0);
    EXPECT_EQ(j["quality_after"]["residual"]["undefined_vertices"], 0);
    EXPECT_LT(j["improve"]["max_residual"].get<double>(), 1e-6);
    EXPECT_EQ(j["field"]["undefined_samples"].get<long long>() > 0, c.undefined_somewhere);
  }
}

// F = 1/x − 1 jumps from −∞ to +∞ at x = 0: the sign change there is a pole, not a zero. The
// mesh is the plane x = 1 alone.
TEST(HostileFields, APoleGetsNoWall) {
  const std::string dir = fresh_dir("hostile_pole");
  const auto r = run_command(zs("mesh '1/x - 1' --clip sphere:2 -r 48 -o " + dir + "/p.obj"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<Vec3> v = obj_vertices(dir + "/p.obj");
  ASSERT_FALSE(v.empty());
  for (const Vec3& p : v) ASSERT_NEAR(p.x(), 1.0, 1e-6) << p.transpose();
  // 1/(x² + y² − 1) has no zero at all, only a pole on a cylinder.
  const auto none =
      run_command(zs("mesh '1/(x^2 + y^2 - 1)' --clip sphere:2 -r 32 -o " + dir + "/none.obj"));
  ASSERT_EQ(none.exit_code, 0) << none.output;
  EXPECT_TRUE(obj_vertices(dir + "/none.obj").empty());
  EXPECT_NE(none.output.find("found no surface"), std::string::npos) << none.output;
}

// F ≡ 0: every point is on F = 0. mesh, sample and render say so alike and put nothing on
// it: no vertex, no floater, no ray that hits (the clip is not drawn as a surface).
TEST(HostileFields, AVanishingFieldIsNoSurfaceForMeshSampleAndRender) {
  const std::string dir = fresh_dir("hostile_zero");
  // The last two are no polynomials: the ray tracer would take interval arithmetic, which
  // finds F = 0 on every ray.
  for (const std::string eq : {"0", "x - x", "sin(x) - sin(x)", "0*exp(x)"}) {
    SCOPED_TRACE(eq);
    const auto m = run_command(zs("mesh '" + eq + "' --clip sphere:2 -o " + dir + "/z.obj"));
    EXPECT_EQ(m.exit_code, 0) << m.output;
    EXPECT_NE(m.output.find("vanishes identically"), std::string::npos) << m.output;
    EXPECT_TRUE(obj_vertices(dir + "/z.obj").empty());
    const auto s = run_command(zs("sample '" + eq + "' --clip sphere:2 --ascii -o " + dir +
                                  "/z.ply --stats " + dir + "/z.json"));
    EXPECT_EQ(s.exit_code, m.exit_code) << s.output;
    EXPECT_NE(s.output.find("vanishes identically"), std::string::npos) << s.output;
    EXPECT_TRUE(ply_points(dir + "/z.ply").empty());
    const auto j = nlohmann::json::parse(read_text(dir + "/z.json"));
    EXPECT_TRUE(j["field"]["vanishes_identically"].get<bool>());
    const auto r = run_command(zs("render '" + eq + "' --clip sphere:2 --size 32x32 -o " + dir +
                                  "/z.png --stats " + dir + "/r.json"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("vanishes identically"), std::string::npos) << r.output;
    const auto rj = nlohmann::json::parse(read_text(dir + "/r.json"));
    EXPECT_EQ(rj["hits"].get<long long>(), 0);
    EXPECT_GT(rj["rays"].get<long long>(), 0);
  }
}

// Floaters never leave the clip or stay where F is undefined; the file holds finite numbers.
TEST(HostileFields, FloatersStayWhereFIsDefined) {
  const std::string dir = fresh_dir("hostile_sample");
  const auto r =
      run_command(zs("sample 'sqrt(x) + y^2 + z^2 - 1' --clip sphere:2 --ascii "
                     "--steps 150 --max-count 600 -o " +
                     dir + "/s.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("F is undefined (NaN or infinite) on"), std::string::npos) << r.output;
  EXPECT_FALSE(has_non_finite_word(read_text(dir + "/s.ply")));
  const std::vector<Vec3> v = ply_points(dir + "/s.ply");
  ASSERT_GT(v.size(), 50u);
  for (const Vec3& p : v) {
    ASSERT_GE(p.x(), 0) << p.transpose();
    ASSERT_LE(p.norm(), 2 * (1 + 1e-9)) << p.transpose();
  }
}

// (x² + y² + z²)^1000 − 1: |F|/|∇F| is r/2000 however far a point is from the sphere, so a
// first-order pull crawls. Settled floaters lie on the unit sphere.
TEST(HostileFields, FloatersOfAHighDegreeSphereSettleOnIt) {
  const std::string dir = fresh_dir("hostile_degree");
  const auto r =
      run_command(zs("sample '(x^2 + y^2 + z^2)^1000 - 1' --clip sphere:2 --ascii "
                     "--max-count 400 -o " +
                     dir + "/h.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("settled at step"), std::string::npos) << r.output;
  const std::vector<Vec3> v = ply_points(dir + "/h.ply");
  ASSERT_GT(v.size(), 20u);
  for (const Vec3& p : v) ASSERT_NEAR(p.norm(), 1.0, 1e-3) << p.transpose();
}

// F undefined everywhere on the rays: each ray's interval search has a budget, so the picture
// is made in bounded time (a hang guard, not a speed test) and the give-ups are reported.
TEST(HostileFields, RenderOfAnUndefinedFieldEndsAndSaysSo) {
  const std::string dir = fresh_dir("hostile_render");
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = run_command(zs("render '1/(x-x) - 1' --clip sphere:2 --size 200x200 -o " + dir +
                                "/r.png --stats " + dir + "/r.json"));
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_LT(seconds, 120);
  EXPECT_NE(r.output.find("F is undefined (NaN or infinite) on 100.0% of the clip"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("gave up"), std::string::npos) << r.output;
  const auto j = nlohmann::json::parse(read_text(dir + "/r.json"));
  EXPECT_GT(j["abandoned_rays"].get<long long>(), 0);
  EXPECT_EQ(j["hits"].get<long long>(), 0);
}

// Every exported number is finite, or the export is refused (exit 2) and nothing is written.
TEST(HostileFields, ExportsRefuseNonFiniteCoefficients) {
  const std::string dir = fresh_dir("hostile_export");
  for (const std::string eq : {"x/0 + y", "sqrt(-1) + x", "0/0*x^2 + y"}) {
    SCOPED_TRACE(eq);
    const std::string pov = dir + "/e.pov";
    const auto r = run_command(zs("export '" + eq + "' --clip sphere:2 -o " + pov));
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("not finite"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(pov));
  }
  const auto ok =
      run_command(zs("export 'x^2 + y^2 + z^2 - 1' --clip sphere:2 -o " + dir + "/ok.pov"));
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_FALSE(has_non_finite_word(read_text(dir + "/ok.pov")));
}

}  // namespace
}  // namespace zeroset::test
