// The Kummer family over its whole range through the command line (docs/singular.md, "The
// Kummer family"): the tetrahedral limit renders, clips given as expressions of the parameters
// work, and bad ones exit 2.
#include <gtest/gtest.h>

#include <cstdlib>
#include <set>
#include <string>

#include "cli/cli_support.h"
#include "zeroset/io/image.h"

namespace zeroset {
namespace {

using test::run_command;
using test::temp_dir;
using test::zs;

struct Coverage {
  double covered = 0;   ///< fraction of pixels unlike the background (the corner's colour)
  double speckles = 0;  ///< fraction of covered pixels whose four neighbours are background
  std::size_t colours = 0;
};

Coverage coverage(const Image& img) {
  const std::uint8_t* bg = img.pixel(0, 0);
  auto is_bg = [&](int x, int y) {
    const std::uint8_t* p = img.pixel(x, y);
    for (int c = 0; c < 3; ++c)
      if (std::abs(int(p[c]) - int(bg[c])) > 8) return false;
    return true;
  };
  long covered = 0, speckles = 0;
  std::set<int> colours;
  for (int y = 1; y + 1 < img.height; ++y)
    for (int x = 1; x + 1 < img.width; ++x) {
      if (is_bg(x, y)) continue;
      ++covered;
      const std::uint8_t* p = img.pixel(x, y);
      colours.insert(p[0] << 16 | p[1] << 8 | p[2]);
      if (is_bg(x - 1, y) && is_bg(x + 1, y) && is_bg(x, y - 1) && is_bg(x, y + 1)) ++speckles;
    }
  const double inner = double(img.width - 2) * (img.height - 2);
  return {covered / inner, covered ? double(speckles) / covered : 0.0, colours.size()};
}

TEST(KummerFamily, RendersOverTheWholeRange) {
  // mu = 10: the clipped surface fills a good part of the picture, shaded, without scattered
  // pixels. At mu = 1.28e6 the clip holding every node is 1.33e6 wide and the surface near it
  // is tubes along the six edge lines far thinner than a pixel (docs/singular.md): drawn, but
  // only as lines.
  for (const char* mu : {"10", "1280000"}) {
    const std::string png = temp_dir() + "/kummer-" + mu + ".png";
    const auto r = run_command(
        zs(std::string("-q render kummer --param mu=") + mu + " --size 96x96 --aa 1 -o " + png));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const Coverage c = coverage(read_image(png));
    if (std::string(mu) == "10") {
      EXPECT_GT(c.covered, 0.15) << mu;
      EXPECT_LT(c.covered, 0.9) << mu;
      EXPECT_GT(c.colours, 50u) << mu;
      EXPECT_LT(c.speckles, 0.01) << mu;
    } else {
      EXPECT_GT(c.covered, 0.001) << mu;
      EXPECT_LT(c.covered, 0.2) << mu;
    }
  }
}

TEST(KummerFamily, InfoListsAllSixteenNodesAtTheEndOfTheRange) {
  const auto r = run_command(zs("info kummer --param mu=1280000"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("16 known"), std::string::npos) << r.output;
}

TEST(KummerFamily, ClipExpressionsOnTheCommandLine) {
  const auto ok =
      run_command(zs("info \"x^2 + y^2 + z^2 - a\" --param a=4 --clip \"sphere:1.5*sqrt(a)\""));
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_NE(ok.output.find("sphere:1.5*sqrt(a)"), std::string::npos) << ok.output;
  for (const char* clip : {"sphere:b", "sphere:sqrt(a", "sphere:x*a", "sphere:log(a-4)",
                           "sphere:a-5", "sphere:a*1e7", "box:a,0,0,0,1,1"}) {
    const auto r = run_command(
        zs(std::string("info \"x^2 + y^2 + z^2 - a\" --param a=4 --clip \"") + clip + "\""));
    EXPECT_EQ(r.exit_code, 2) << clip << "\n" << r.output;
    EXPECT_NE(r.output.find(clip), std::string::npos) << clip << "\n" << r.output;
    EXPECT_EQ(r.output.find("terminate"), std::string::npos) << clip << r.output;
  }
  // Beyond the clip's limits only at some parameter values: refused there.
  const auto far = run_command(zs("info kummer --param mu=1e8"));
  EXPECT_EQ(far.exit_code, 2) << far.output;
  EXPECT_NE(far.output.find("mu = 1e+08"), std::string::npos) << far.output;
}

}  // namespace
}  // namespace zeroset
