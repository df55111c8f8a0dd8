// SURFER's .jsurf files: the Java properties syntax, the conventions of jsurf's transforms,
// errors that name the line, and writing the file back.
#include "zeroset/surface/jsurf.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "properties_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset {
namespace {

const std::string kKummer =
    "(3-a)*(x^2+y^2+z^2-a)^2-(3*a-1)*(1-z-sqrt(2)*x)*(1-z+sqrt(2)*x)*(1+z+sqrt(2)*y)*"
    "(1+z-sqrt(2)*y)";

// The frame SURFER's rotation_matrix holds as columns (x right, y up, z towards the viewer),
// for an orbit camera at azimuth `az`, elevation `el`, turned by `roll` (degrees), worked out
// here from the definitions in surface.h rather than through Camera::frame.
Mat3 orbit_rotation(double az, double el, double roll) {
  const double a = az * M_PI / 180, e = el * M_PI / 180, r = roll * M_PI / 180;
  const Vec3 back(std::cos(e) * std::cos(a), std::cos(e) * std::sin(a), std::sin(e));
  const Vec3 right0 = Vec3(-back).cross(Vec3::UnitZ()).normalized();
  const Vec3 up0 = right0.cross(-back);
  Mat3 m;
  m.col(0) = std::cos(r) * right0 + std::sin(r) * up0;
  m.col(1) = -std::sin(r) * right0 + std::cos(r) * up0;
  m.col(2) = back;
  return m;
}

std::string row_major(const Mat3& m, const Vec3& t = Vec3::Zero()) {
  std::string out;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      const double v = r < 3 ? (c < 3 ? m(r, c) : t[r]) : (c == 3 ? 1.0 : 0.0);
      char buf[40];
      std::snprintf(buf, sizeof buf, "%.17g", v);
      if (!out.empty()) out += ' ';
      out += buf;
    }
  return out;
}

std::string error_of(const std::string& text) {
  try {
    jsurf_to_scene(text, "bad.jsurf");
  } catch (const BadInput& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(JavaProperties, ReadsEveryFormOfLine) {
  const std::string text =
      "# comment\r\n"
      "   ! another comment \\\r\n"
      "plain=1\r\n"
      "colon : two words \r\n"
      "blank\tthree\r"
      "cont = first \\\n"
      "       second \\\\\n"
      "after=x\n"
      "esc\\=key\\:x = \\t\\u0041\\u00e9\\n\\q\n"
      "empty\n"
      "plain=replaced";
  const auto p = detail::parse_properties(text, "t");
  EXPECT_EQ(p.at("plain").value, "replaced");
  EXPECT_EQ(p.at("plain").line, 11);
  EXPECT_EQ(p.at("colon").value, "two words ");
  EXPECT_EQ(p.at("colon").line, 4);
  EXPECT_EQ(p.at("blank").value, "three");
  EXPECT_EQ(p.at("blank").line, 5);
  EXPECT_EQ(p.at("cont").value, "first second \\");
  EXPECT_EQ(p.at("cont").line, 6);
  EXPECT_EQ(p.at("after").line, 8);
  EXPECT_EQ(p.at("esc=key:x").value, "\tA\xC3\xA9\nq");
  EXPECT_EQ(p.at("empty").value, "");
  EXPECT_EQ(p.count("!"), 0u);
  EXPECT_EQ(p.size(), 7u);
}

TEST(JavaProperties, EscapingGivesTheTextBack) {
  for (const std::string s :
       {"a b\\c", " lead", "tab\tnl\numl\xC3\xA4 emoji\xF0\x9F\x98\x80 #!=:"}) {
    const std::string text =
        "k" + detail::escape_property("=: #", true) + "=" + detail::escape_property(s) + "\n";
    const auto p = detail::parse_properties(text, "t");
    ASSERT_EQ(p.count("k=: #"), 1u) << text;
    EXPECT_EQ(p.at("k=: #").value, s) << text;
  }
}

TEST(Jsurf, ReadsEquationParametersClipAndCamera) {
  const Mat3 rot = orbit_rotation(40, 25, 15);
  const std::string text = "surface_equation=" + kKummer +
                           "\n"
                           "surface_parameter_a=1.5\n"
                           "surface_parameter_b=7\n"  // not in the equation: ignored
                           "scale_factor=0.3\n"
                           "rotation_matrix=" +
                           row_major(rot) +
                           "\n"
                           "camera_type=PERSPECTIVE_CAMERA\n"
                           "camera_fov_y=35\n"
                           "camera_transform=1 0 0 0 0 1 0 0 0 0 1 -3 0 0 0 1\n"
                           "background_color=0.2 0.4 0.6\n"
                           "front_material_color=1 0.5 0\n"
                           "front_material_ambient_intensity=0.25\n"
                           "trace_patterns=false\n"
                           "antialiasing_quality=2\n";
  const Scene scene = jsurf_to_scene(text, "k.jsurf");
  const Surface& s = scene.surface;
  ASSERT_EQ(s.field.parameter_names(), std::vector<std::string>{"a"});
  EXPECT_EQ(s.field.parameter_values()[0], 1.5);
  ASSERT_EQ(s.clip.spheres.size(), 1u);
  EXPECT_TRUE(s.clip.planes.empty());
  const double radius = std::pow(10.0, 0.3);  // radius = 10^scale_factor
  EXPECT_EQ(s.clip.spheres[0].radius, radius);
  EXPECT_NEAR(s.camera.azimuth_deg, 40, 1e-9);
  EXPECT_NEAR(s.camera.elevation_deg, 25, 1e-9);
  EXPECT_NEAR(s.camera.roll_deg, 15, 1e-9);
  EXPECT_NEAR(s.camera.distance, 3 * radius, 1e-12);  // camera_transform is in clip radii
  EXPECT_NEAR(s.camera.target.norm(), 0, 1e-12);
  EXPECT_EQ(s.camera.fov_deg, 35);
  const CameraFrame f = s.camera.frame(radius);
  EXPECT_NEAR((f.right - rot.col(0)).norm(), 0, 1e-12);
  EXPECT_NEAR((f.up - rot.col(1)).norm(), 0, 1e-12);
  EXPECT_NEAR((f.forward + rot.col(2)).norm(), 0, 1e-12);
  const auto& render = scene.settings.at("render");
  EXPECT_NEAR(render.at("background")[0].get<double>(), std::pow(0.2, 2.2), 1e-15);
  EXPECT_NEAR(render.at("front").at("diffuse")[1].get<double>(), std::pow(0.5, 2.2), 1e-15);
  EXPECT_EQ(render.at("front").at("ambient").get<double>(), 0.25);
  EXPECT_FALSE(render.contains("back"));
  EXPECT_FALSE(render.contains("lights"));  // none given: zeroset's own rig
}

TEST(Jsurf, PointLightsBecomeDirectionsFromTheClipCentre) {
  const std::string text =
      "surface_equation=x^2+y^2+z^2-1\n"
      "camera_transform=1 0 0 0 0 1 0 0 0 0 1 -4 0 0 0 1\n"
      "light_status_0=ON\nlight_position_0=0 10 -4\nlight_color_0=1 1 1\n"
      "light_intensity_0=0.5\n"
      "light_status_1=OFF\nlight_position_1=5 5 5\n"
      "light_position_2=1 1 1\n";  // no status: off, as in jsurf
  const auto lights = jsurf_to_scene(text, "l.jsurf").settings.at("render").at("lights");
  ASSERT_EQ(lights.size(), 1u);
  EXPECT_EQ(lights[0].at("direction"), nlohmann::json({0.0, 10.0, 0.0}));
  EXPECT_NEAR(lights[0].at("color")[0].get<double>(), std::pow(0.5, 2.2), 1e-15);
  EXPECT_TRUE(lights[0].at("follows_camera").get<bool>());
}

TEST(Jsurf, ErrorsNameTheFileAndLine) {
  EXPECT_NE(error_of("# nothing\nscale_factor=1\n").find("bad.jsurf: no surface_equation"),
            std::string::npos);
  EXPECT_NE(error_of("surface_equation=x^2-1\n\nscale_factor=1,5\n")
                .find("bad.jsurf:3: "
                      "scale_factor"),
            std::string::npos);
  EXPECT_NE(error_of("surface_equation=x^2+-*1\n")
                .find("bad.jsurf:1: surface_equation: cannot "
                      "read"),
            std::string::npos);
  EXPECT_NE(error_of("a=1\nsurface_equation=x\\u00g1\n").find("bad.jsurf:2: malformed"),
            std::string::npos);
  EXPECT_NE(error_of("surface_equation=x\nsurface_parameter_a=\\\n  zwei\n").find("bad.jsurf:2:"),
            std::string::npos);
  EXPECT_NE(error_of("surface_equation=x\nrotation_matrix=1 0 0 0 0 1 0 0 0 0 1 0 0 0 0\n")
                .find("bad.jsurf:2: rotation_matrix: expected 16 numbers, found 15"),
            std::string::npos);
  // A shear, a mirror: not something a camera shows.
  EXPECT_NE(error_of("surface_equation=x\nrotation_matrix=1 1 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n")
                .find("bad.jsurf:2: rotation_matrix"),
            std::string::npos);
  EXPECT_NE(error_of("surface_equation=x\nrotation_matrix=-1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1\n")
                .find("bad.jsurf:2: rotation_matrix"),
            std::string::npos);
  EXPECT_NE(error_of("surface_equation=x\ncamera_type=FISHEYE_CAMERA\n")
                .find("bad.jsurf:2: camera_type: 'FISHEYE_CAMERA' is neither"),
            std::string::npos);
  EXPECT_NE(error_of("surface_equation=x\nbackground_color=1 2 0\n").find("bad.jsurf:2"),
            std::string::npos);
  EXPECT_NE(error_of("surface_equation=x\ncamera_fov_y=0\n").find("bad.jsurf:2"),
            std::string::npos);
  EXPECT_NE(error_of("surface_equation=x\ncamera_transform=1 0 0 0 0 1 0 0 0 0 1 3 0 0 0 1\n")
                .find("bad.jsurf:2: camera_transform: the camera looks away"),
            std::string::npos);
}

TEST(Jsurf, ResolveSceneOpensFilesAndAppliesOverrides) {
  const auto path = (std::filesystem::temp_directory_path() / "zeroset_jsurf_test.jsurf").string();
  std::ofstream(path) << "surface_equation=x^2+y^2+z^2-a\nsurface_parameter_a=0.5\n";
  const Scene scene = resolve_scene(path, {.params = {{"a", 0.75}}, .clip_specs = {}});
  EXPECT_EQ(scene.surface.field.parameter_values()[0], 0.75);
  EXPECT_EQ(scene.surface.clip.spheres.at(0).radius, 1.0);  // no scale_factor: 10^0
  EXPECT_EQ(scene.surface.camera.distance, 0.0);            // no camera_transform: fitted
  std::filesystem::remove(path);
}

TEST(Jsurf, WritingRenamesParametersAndReadsBackTheSameScene) {
  Scene scene = resolve_scene(
      "p = 1 - z - sqrt(2)*x; q = 1 - z + sqrt(2)*x\n"
      "(3 - mu)*(x^2 + y^2 + z^2 - mu)^2 - (3*mu - 1)*p*q*(1+z)**2 + b*pi",
      {.params = {{"mu", 1.25}, {"b", 0.5}}, .clip_specs = {"sphere:2.5"}});
  scene.surface.camera = {.azimuth_deg = -70,
                          .elevation_deg = 80,
                          .distance = 9,
                          .fov_deg = 28,
                          .target = Vec3(0.1, -0.2, 0.3),
                          .roll_deg = -35};
  scene.settings["render"] = {
      {"background", {0.25, 0.5, 1.0}},
      {"front", {{"diffuse", {0.5, 0.25, 0.125}}, {"ambient", 0.2}}},
      {"lights", {{{"direction", {0, 0, 2}}, {"color", {1, 1, 1}}, {"follows_camera", false}}}}};
  const std::string text = scene_to_jsurf(scene);
  EXPECT_NE(text.find("surface_parameter_a=1.25"), std::string::npos) << text;  // mu -> a
  EXPECT_NE(text.find("surface_parameter_b=0.5"), std::string::npos) << text;
  EXPECT_EQ(text.find("mu"), std::string::npos) << text;
  EXPECT_EQ(text.find("**"), std::string::npos) << text;
  const Scene back = jsurf_to_scene(text, "w.jsurf");
  const Surface& s = back.surface;
  EXPECT_EQ(s.field.parameter_names(), (std::vector<std::string>{"a", "b"}));
  for (const Vec3& p : {Vec3(0.3, -0.7, 0.2), Vec3(1.1, 0.4, -0.9)})
    EXPECT_NEAR(s.field.polynomial().value(p), scene.surface.field.polynomial().value(p), 1e-12);
  EXPECT_NEAR(s.clip.spheres.at(0).radius, 2.5, 1e-14);
  const CameraFrame a = scene.surface.camera.frame(2.5), b = s.camera.frame(2.5);
  EXPECT_NEAR((a.eye - b.eye).norm(), 0, 1e-12);
  EXPECT_NEAR((a.right - b.right).norm(), 0, 1e-12);
  EXPECT_NEAR((a.up - b.up).norm(), 0, 1e-12);
  EXPECT_NEAR((a.forward - b.forward).norm(), 0, 1e-12);
  EXPECT_EQ(s.camera.fov_deg, 28);
  const auto& render = back.settings.at("render");
  EXPECT_NEAR(render.at("background")[1].get<double>(), 0.5, 1e-14);
  EXPECT_NEAR(render.at("front").at("diffuse")[2].get<double>(), 0.125, 1e-14);
  // The world light (straight up) arrives as a direction in the camera's frame.
  const auto& d = render.at("lights").at(0).at("direction");
  const Vec3 up_in_camera = Vec3(d[0].get<double>(), d[1].get<double>(), d[2].get<double>());
  const Vec3 world =
      up_in_camera.x() * b.right + up_in_camera.y() * b.up - up_in_camera.z() * b.forward;
  EXPECT_NEAR((world.normalized() - Vec3::UnitZ()).norm(), 0, 1e-9);
}

TEST(Jsurf, WritingRefusesWhatSurferCannotShow) {
  auto refuses = [](const std::string& spec, const std::vector<std::string>& clip,
                    const std::string& words) {
    try {
      SurfaceOverrides o{.params = {}, .clip_specs = clip};
      for (const char* name : {"a", "b", "c", "d", "e1"})
        if (spec.find(name) != std::string::npos) o.params[name] = 1;
      Scene scene = resolve_scene(spec, o);
      scene_to_jsurf(scene);
      ADD_FAILURE() << spec;
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  refuses("a*x^2 + b*y^2 + c*z^2 - d - e1", {"sphere:2"}, "at most 4 parameters");
  refuses("x^2 + y^2 - z^2", {"sphere:2", "plane:0,0,1,0.5"}, "one sphere");
  refuses("x^2 + y^2 - z^2", {"sphere:2@1,0,0"}, "centred elsewhere");
  refuses("x^2 + y^2 - z^2", {"box:2"}, "one sphere");
  refuses("sin(x) + y^2 + z^2 - 1", {"sphere:2"}, "not a polynomial");
  refuses("x/0 + y", {"sphere:2"}, "is not finite");
}

// A file as SURFER saves it (java.util.Properties.store): the header comment and date, keys
// in hash order, escaped ':' and '=' and \u escapes in values, an orthographic camera.
const std::string kSurferOrtho =
    "#jSurfer\n"
    "#Mon Sep 14 13:17:06 CEST 2015\n"
    "surface_parameter_d=0.0\n"
    "surface_parameter_c=0.0\n"
    "surface_parameter_b=0.0\n"
    "surface_parameter_a=0.5\n"
    "camera_height=2.0\n"
    "camera_type=ORTHOGRAPHIC_CAMERA\n"
    "camera_transform=1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0 -1.0 0.0 0.0 0.0 1.0\n"
    "rotation_matrix=1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0 0.0 0.0 0.0 0.0 1.0\n"
    "scale_factor=0.0\n"
    "surface_equation=x^2+y^2+z^2-(a+b+c+d)^2\n"
    "surface_name=Kugel\\: r \\= a \\u00e4\n"
    "background_color=1.0 1.0 1.0\n";

TEST(Jsurf, OpensSurferOrthographicFiles) {
  const Scene scene = jsurf_to_scene(kSurferOrtho, "kugel.jsurf");
  const Camera& c = scene.surface.camera;
  EXPECT_EQ(c.projection, Projection::orthographic);
  EXPECT_NEAR(c.ortho_height, 2.0, 1e-12);  // camera units are the clip radius, 1 here
  EXPECT_EQ(scene.surface.title, "Kugel: r = a \u00e4");
  EXPECT_DOUBLE_EQ(scene.surface.field.parameter_values()[scene.surface.field.parameter_index("a")],
                   0.5);
  // Looking down -z (rotation_matrix is the identity): the camera's back direction is +z.
  EXPECT_NEAR(c.elevation_deg, 90, 1e-9);
  // A zoomed view (scale_factor 0.5: a clip radius of 10^0.5) scales the height alike.
  std::string zoomed = kSurferOrtho;
  zoomed.replace(zoomed.find("scale_factor=0.0"), 16, "scale_factor=0.5");
  EXPECT_NEAR(jsurf_to_scene(zoomed, "z.jsurf").surface.camera.ortho_height,
              2.0 * std::pow(10.0, 0.5), 1e-9);
  // Without camera_height the picture fits the clip sphere.
  std::string fit = kSurferOrtho;
  fit.erase(fit.find("camera_height=2.0\n"), 18);
  EXPECT_EQ(jsurf_to_scene(fit, "f.jsurf").surface.camera.ortho_height, 0);
}

TEST(Jsurf, OrthographicCameraRoundTrips) {
  Scene scene = jsurf_to_scene(kSurferOrtho, "kugel.jsurf");
  const std::string text = scene_to_jsurf(scene);
  EXPECT_NE(text.find("camera_type=ORTHOGRAPHIC_CAMERA\n"), std::string::npos) << text;
  EXPECT_NE(text.find("camera_height=2\n"), std::string::npos) << text;
  const Scene back = jsurf_to_scene(text, "back.jsurf");
  EXPECT_EQ(back.surface.camera.projection, Projection::orthographic);
  EXPECT_NEAR(back.surface.camera.ortho_height, 2.0, 1e-12);
  // A perspective scene stays one.
  scene.surface.camera.projection = Projection::perspective;
  const std::string persp = scene_to_jsurf(scene);
  EXPECT_NE(persp.find("camera_type=PERSPECTIVE_CAMERA\n"), std::string::npos);
  EXPECT_EQ(persp.find("camera_height"), std::string::npos);
  EXPECT_EQ(jsurf_to_scene(persp, "p.jsurf").surface.camera.projection, Projection::perspective);
}

TEST(Jsurf, RefusesBadOrthographicHeights) {
  for (const char* bad : {"-1", "0", "NaN", "1e300", "two"}) {
    std::string text = kSurferOrtho;
    text.replace(text.find("camera_height=2.0"), 17, std::string("camera_height=") + bad);
    const std::string e = error_of(text);
    EXPECT_NE(e.find("bad.jsurf:7: camera_height"), std::string::npos) << bad << ": " << e;
  }
}

}  // namespace
}  // namespace zeroset
