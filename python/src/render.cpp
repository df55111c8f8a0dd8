// Surface.render and Surface.export_pov: the options of `zeroset render` / `zeroset export`
// (apps/cli/cmd_render.cpp) built the same way, then render_surface or write_pov_scene.
#include <nlohmann/json.hpp>
#include <optional>
#include <tuple>

#include "bindings.h"
#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/render/pov_export.h"
#include "zeroset/render/render.h"
#include "zeroset/render/settings.h"
#include "zeroset/surface/settings.h"

namespace zeroset::python {
namespace {

using namespace pybind11::literals;

/// How the picture looks; unset members keep the scene file's value or the default.
struct Look {
  std::optional<std::pair<int, int>> size;
  std::optional<int> aa;
  std::optional<std::vector<double>> camera;  // azimuth, elevation[, distance]
  std::optional<std::vector<double>> target;
  std::optional<double> fov;
  std::optional<std::string> background, front, back;
  int threads = 0;
  std::optional<std::string> projection;  // perspective | ortho[:height]
};

// Defaults, then the scene file's "render" object, then what was given, validated by the
// library's checks (as `zeroset render` builds its options).
RenderOptions options(const PySurface& s, const Look& look) {
  const Surface& surface = s.surface();
  RenderOptions o;
  o.samples = 2;
  if (s.scene.settings.is_object() && s.scene.settings.contains("render"))
    apply_render_settings(s.scene.settings["render"], o, s.spec);
  if (look.size) std::tie(o.width, o.height) = *look.size;
  if (look.aa) o.samples = *look.aa;
  o.threads = look.threads;
  Camera cam = surface.camera;
  if (look.camera) {
    const std::vector<double>& v = *look.camera;
    if (v.size() < 2 || v.size() > 3)
      throw InvalidArgument("camera", std::to_string(v.size()) + " numbers",
                            "expected (azimuth, elevation[, distance])");
    cam.azimuth_deg = v[0];
    cam.elevation_deg = v[1];
    if (v.size() == 3) cam.distance = v[2];
  }
  if (look.target) {
    if (look.target->size() != 3)
      throw InvalidArgument("target", std::to_string(look.target->size()) + " numbers",
                            "expected three numbers (x, y, z)");
    cam.target = Vec3((*look.target)[0], (*look.target)[1], (*look.target)[2]);
  }
  if (look.fov) cam.fov_deg = *look.fov;
  if (look.projection) cam = with_projection(cam, *look.projection, "projection");
  validate_camera(cam);
  o.camera = cam;
  if (look.background) o.background = parse_display_color(*look.background, "background");
  if (look.front) o.front.diffuse = parse_display_color(*look.front, "front");
  if (look.back) o.back.diffuse = parse_display_color(*look.back, "back");
  validate_settings(o);
  return o;
}

Look look_of(std::optional<std::pair<int, int>> size, std::optional<int> aa,
             std::optional<std::vector<double>> camera, std::optional<std::vector<double>> target,
             std::optional<double> fov, std::optional<std::string> background,
             std::optional<std::string> front, std::optional<std::string> back, int threads,
             std::optional<std::string> projection) {
  return Look{size, aa, camera, target, fov, background, front, back, threads, projection};
}

#define ZS_LOOK_ARGS                                                                            \
  "size"_a = py::none(), "aa"_a = py::none(), "camera"_a = py::none(), "target"_a = py::none(), \
  "fov"_a = py::none(), "background"_a = py::none(), "front"_a = py::none(),                    \
  "back"_a = py::none(), "threads"_a = 0, "projection"_a = py::none()

}  // namespace

void bind_render(py::module_& m) {
  py::class_<Look>(m, "_Look").def(py::init(&look_of), ZS_LOOK_ARGS);
  m.def(
      "_render",
      [](const PySurface& s, const Look& look, bool show_singular) {
        RenderOptions o = options(s, look);
        Image image;
        RenderStats rs;
        const Surface surface = s.surface();  // its own copy while the GIL is released
        run_interruptible([&](std::stop_token stop) {
          // As `zeroset render --show-singular`: the set when the clip is bounded.
          if (show_singular && surface.clip.is_bounded())
            o.singular_overlay = SingularOverlay{.set = find_singular_set(surface, {}, stop)};
          if (!stop.stop_requested()) image = render_surface(surface, o, &rs, stop);
        });
        nlohmann::json j = rs.to_json();
        j.update({{"width", o.width}, {"height", o.height}, {"samples", o.samples}});
        return py::make_tuple(to_array(image), py::module_::import("json").attr("loads")(j.dump()));
      },
      "surface"_a, "look"_a, "show_singular"_a);
  m.def(
      "_pov_scene",
      [](const PySurface& s, const Look& look) { return pov_scene(s.surface(), options(s, look)); },
      "surface"_a, "look"_a);
  m.def(
      "_export_pov",
      [](const PySurface& s, const Look& look, const std::string& path) {
        if (file_extension(path) != "pov")
          throw InvalidArgument("path", path, "the file name must end in .pov");
        check_writable(path);
        write_pov_scene(s.surface(), options(s, look), path);
      },
      "surface"_a, "look"_a, "path"_a);
  m.def(
      "write_image",
      [](const py::array_t<std::uint8_t, py::array::c_style>& rgb, const std::string& path) {
        write_image(image_of(rgb), path);
      },
      "image"_a, "path"_a, "Writes an (h, w, 3) uint8 array as PNG or PPM (by the extension).");
  m.def(
      "encode_png",
      [](const py::array_t<std::uint8_t, py::array::c_style>& rgb) {
        const std::vector<std::uint8_t> bytes = encode_png(image_of(rgb));
        return py::bytes(reinterpret_cast<const char*>(bytes.data()), bytes.size());
      },
      "image"_a, "The PNG file's bytes of an (h, w, 3) uint8 array.");
  m.def(
      "read_image", [](const std::string& path) { return to_array(read_image(path)); }, "path"_a,
      "Reads a PNG or binary PPM as an (h, w, 3) uint8 array.");
}

}  // namespace zeroset::python
