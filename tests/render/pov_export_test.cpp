#include "zeroset/render/pov_export.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "render/image_masks.h"
#include "support/run_command.h"
#include "zeroset/error.h"
#include "zeroset/io/image.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;

/// A fresh directory under the system's temporary directory, removed afterwards.
class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() /
            ("zeroset-pov-" + std::to_string(::getpid()) + "-" + std::to_string(counter_++));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
  static inline int counter_ = 0;
};

bool have_povray() { return test::run_command("command -v povray").exit_code == 0; }

/// Renders the exported scene with POV-Ray and with zeroset, and returns the IoU of the
/// surface masks.
double pov_agreement(const Surface& s, const RenderOptions& o) {
  TempDir dir;
  const std::string pov = dir.file("scene.pov"), png = dir.file("pov.png");
  write_pov_scene(s, o, pov);
  const auto r = test::run_command("povray -D -V +W" + std::to_string(o.width) + " +H" +
                                   std::to_string(o.height) + " +I" + pov + " +O" + png);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  if (r.exit_code != 0) return 0;
  const Image theirs = read_image(png);
  const Image ours = render_surface(s, o);
  EXPECT_EQ(theirs.width, ours.width);
  EXPECT_EQ(theirs.height, ours.height);
  return test::intersection_over_union(test::surface_mask(theirs, o.background),
                                       test::surface_mask(ours, o.background));
}

TEST(PovExport, PovRayDrawsTheSameSurfaceAsOurRenderer) {
  if (!have_povray()) GTEST_SKIP() << "povray is not installed";
  RenderOptions o;
  o.width = o.height = 200;
  for (const char* name : {"kummer", "cayley", "barth6"}) {
    const Surface s = make_surface(*find_catalog_entry(name));
    EXPECT_GE(pov_agreement(s, o), 0.97) << name;
  }
}

TEST(PovExport, KeepsCameraOrientationForWideImagesAndClipPlanes) {
  if (!have_povray()) GTEST_SKIP() << "povray is not installed";
  // An asymmetric view of an asymmetric, half-space-clipped surface: a mirrored or rotated
  // camera would not overlap.
  Surface s = surface_from_equation("x^2 + 2*y^2 + z^3 - z - 0.1*x*y");
  s.clip = Clip::sphere(1.6);
  s.clip.add("plane:1,0.3,0,0.7");
  s.camera.azimuth_deg = 70;
  s.camera.elevation_deg = 35;
  RenderOptions o;
  o.width = 240;
  o.height = 160;
  EXPECT_GE(pov_agreement(s, o), 0.97);
}

TEST(PovExport, WritesPolynomialWithSturmAndClip) {
  const Surface s = make_surface(*find_catalog_entry("kummer"));
  const std::string text = pov_scene(s, RenderOptions{});
  EXPECT_NE(text.find("polynomial { 4,"), std::string::npos);
  EXPECT_NE(text.find("sturm"), std::string::npos);
  EXPECT_NE(text.find("clipped_by"), std::string::npos);
  EXPECT_NE(text.find("interior_texture"), std::string::npos);
  EXPECT_NE(text.find("camera"), std::string::npos);
}

TEST(PovExport, WritesAnOrthographicCameraSizedToTheHeight) {
  Surface s = surface_from_equation("x^2 + y^2 + z^2 - 1");
  s.clip = Clip::sphere(1.5);
  s.camera.projection = Projection::orthographic;
  s.camera.ortho_height = 2.5;
  RenderOptions o;
  o.width = 300;
  o.height = 150;
  const std::string pov = pov_scene(s, o);
  EXPECT_NE(pov.find("  orthographic\n"), std::string::npos) << pov;
  EXPECT_EQ(pov.find("  perspective\n"), std::string::npos) << pov;
  EXPECT_NE(pov.find("  up <0, 2.5, 0>\n"), std::string::npos) << pov;
  EXPECT_NE(pov.find("  right <-5, 0, 0>\n"), std::string::npos) << pov;
  EXPECT_EQ(pov.find("angle"), std::string::npos) << pov;
  if (have_povray()) {
    o.height = 300;
    EXPECT_GE(pov_agreement(s, o), 0.97);
  }
}

TEST(PovExport, RejectsNonPolynomialSurface) {
  Surface s = surface_from_equation("sqrt(x^2 + y^2) - z");
  s.clip = Clip::sphere(1);
  EXPECT_THROW(pov_scene(s, RenderOptions{}), BadInput);
}

TEST(PovExport, LeavesNoFileBehindOnError) {
  TempDir dir;
  Surface s = surface_from_equation("x^2 + y^2 - z^2");  // no clip
  const std::string path = dir.file("scene.pov");
  EXPECT_THROW(write_pov_scene(s, RenderOptions{}, path), BadInput);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_THROW(write_pov_scene(make_surface(*find_catalog_entry("sphere")), RenderOptions{},
                               dir.file("missing-dir/scene.pov")),
               IoError);
}

}  // namespace
}  // namespace zeroset
