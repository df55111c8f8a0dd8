// Surface.sample and zeroset.Floaters: the loop of `zeroset sample` (apps/cli/cmd_sample.cpp)
// with the same options, and a floater system to step from Python (animation in a loop).
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <tuple>

#include "bindings.h"
#include "zeroset/error.h"
#include "zeroset/floaters/floaters.h"
#include "zeroset/floaters/ply.h"
#include "zeroset/floaters/sample_surface.h"
#include "zeroset/floaters/settings.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/render/render.h"
#include "zeroset/render/settings.h"
#include "zeroset/surface/settings.h"

namespace zeroset::python {
namespace {

using namespace pybind11::literals;

struct PyFloaters {
  FloaterSystem sys;
  StepStats last;
  bool busy = false;  ///< a call works on `sys` without the GIL (read and set with the GIL held)
};

// Refuses a call while another Python thread steps or draws the system without the GIL.
const PyFloaters& idle(const PyFloaters& f) {
  if (f.busy) throw std::runtime_error("the floater system is busy in another thread");
  return f;
}

/// Marks the system busy for one call that releases the GIL.
struct Busy {
  PyFloaters& f;
  explicit Busy(PyFloaters& floaters) : f(floaters) {
    idle(f);
    f.busy = true;
  }
  ~Busy() { f.busy = false; }
  Busy(const Busy&) = delete;
  Busy& operator=(const Busy&) = delete;
};

py::dict step_dict(const StepStats& s) {
  return py::dict("step"_a = s.step, "count"_a = s.count, "births"_a = s.births,
                  "deaths"_a = s.deaths, "removed"_a = s.removed, "inserted"_a = s.inserted,
                  "median_residual"_a = s.median_residual, "max_residual"_a = s.max_residual,
                  "rms_speed"_a = s.rms_speed, "near_equilibrium"_a = s.near_equilibrium,
                  "converged"_a = s.converged, "seconds"_a = s.seconds);
}

// As `zeroset sample`: the scene file's "floaters" object, then the options given (a JSON object
// with the same keys, read by the same function, so a bad value gets the same words).
FloaterOptions options_from(const PySurface& s, const std::string& given, int threads) {
  FloaterOptions o;
  if (s.scene.settings.contains("floaters"))
    apply_floater_settings(s.scene.settings["floaters"], o, "'" + s.spec + "'");
  apply_floater_options(nlohmann::json::parse(given), o);
  o.threads = threads;
  check_floater_memory(o, o.seed_count > o.max_count ? "seed_count" : "max_count");
  return o;
}

// The values of `sys`'s parameters with `changes` applied (InvalidArgument for an unknown name).
std::vector<double> parameters_with(const FloaterSystem& sys,
                                    const std::map<std::string, double>& changes) {
  const Field& field = sys.surface().field;
  std::vector<double> q(sys.parameters().begin(), sys.parameters().end());
  for (const auto& [name, value] : changes) {
    const int k = field.parameter_index(name);
    if (k < 0)
      throw InvalidArgument(name, std::to_string(value),
                            sys.surface().label() + " has no parameter of that name");
    if (!std::isfinite(value)) throw InvalidArgument(name, std::to_string(value), "must be finite");
    q[static_cast<size_t>(k)] = value;
  }
  return q;
}

// The recipe of `zeroset sample` (sample_surface); the stats are its --stats file, as JSON
// text the module turns into dictionaries, and its warnings go to Python's warnings.
py::tuple sample(const PySurface& s, const std::string& given, std::optional<size_t> steps,
                 size_t max_steps, std::optional<std::tuple<std::string, double, double>> animate,
                 size_t settle_steps, bool quality, int threads) {
  const Surface surface = s.surface();
  SampleRun run;
  run.max_steps = max_steps;
  if (animate) {
    const auto& [name, from, to] = *animate;
    if (!steps || *steps == 0)
      throw InvalidArgument("animate", name, "give the number of animated steps with steps=N");
    run.animation = SampleAnimation{
        .parameter = name, .from = from, .to = to, .steps = *steps, .settle_steps = settle_steps};
  } else {
    run.steps = steps;
  }
  if (quality) run.metrics = MetricsOptions{};
  const FloaterOptions options = options_from(s, given, threads);
  std::optional<SampleResult> result;
  run_interruptible(
      [&](std::stop_token stop) { result = sample_surface(surface, options, run, stop); });
  if (!result->system)  // F vanishes identically
    throw InvalidArgument(result->warnings.empty() ? surface.label() + ": there is no surface"
                                                   : result->warnings.front());
  const std::string stats = result->to_json().dump();  // before the floaters move out
  PyFloaters f{std::move(*result->system), result->last, false};
  return py::make_tuple(std::move(f), stats, result->warnings);
}

// Steps `n` times, the parameters moving linearly to `target` when given; each step is whole,
// so an interrupt leaves the system after its last complete step.
py::dict step(PyFloaters& f, size_t n, const std::optional<std::map<std::string, double>>& target) {
  const Busy busy(f);
  std::vector<double> from(f.sys.parameters().begin(), f.sys.parameters().end());
  const std::vector<double> to = target ? parameters_with(f.sys, *target) : from;
  run_interruptible([&](std::stop_token stop) {
    for (size_t k = 1; k <= n && !stop.stop_requested(); ++k) {
      if (!target) {
        f.last = f.sys.step();
        continue;
      }
      std::vector<double> q(from.size());
      for (size_t i = 0; i < q.size(); ++i)
        q[i] = from[i] + (to[i] - from[i]) * static_cast<double>(k) / static_cast<double>(n);
      f.last = f.sys.step(q);
    }
  });
  return step_dict(f.last);
}

py::array_t<double> doubles(std::span<const double> v) {
  return py::array_t<double>(static_cast<py::ssize_t>(v.size()), v.data());
}

}  // namespace

void bind_floaters(py::module_& m) {
  py::class_<PyFloaters>(m, "_Floaters")
      .def("step", &step, "n"_a = 1, "target"_a = py::none())
      .def("set_params",
           [](PyFloaters& f, const std::map<std::string, double>& values) {
             idle(f);
             f.sys.set_parameters(parameters_with(f.sys, values));
           })
      .def("get_params",
           [](const PyFloaters& f) {
             idle(f);
             py::dict d;
             const auto& names = f.sys.surface().field.parameter_names();
             for (size_t k = 0; k < names.size(); ++k) d[py::str(names[k])] = f.sys.parameters()[k];
             return d;
           })
      .def("reset",
           [](PyFloaters& f) {
             idle(f);
             f.sys.reset();
           })
      .def(
          "reseed",
          [](PyFloaters& f, std::uint64_t seed) {
            idle(f);
            f.sys.reseed(seed);
          },
          "seed"_a)
      .def_property_readonly("positions",
                             [](const PyFloaters& f) {
                               idle(f);
                               return to_array(f.sys.positions());
                             })
      .def_property_readonly("normals",
                             [](const PyFloaters& f) {
                               idle(f);
                               return to_array(f.sys.normals());
                             })
      .def_property_readonly("radii",
                             [](const PyFloaters& f) {
                               idle(f);
                               return doubles(f.sys.radii());
                             })
      .def_property_readonly("max_radii",
                             [](const PyFloaters& f) {
                               idle(f);
                               return doubles(f.sys.max_radii());
                             })
      .def_property_readonly("ids",
                             [](const PyFloaters& f) {
                               idle(f);
                               const auto ids = f.sys.ids();
                               return py::array_t<std::uint64_t>(
                                   static_cast<py::ssize_t>(ids.size()), ids.data());
                             })
      .def_property_readonly("count",
                             [](const PyFloaters& f) {
                               idle(f);
                               return f.sys.size();
                             })
      .def_property_readonly("steps_taken",
                             [](const PyFloaters& f) {
                               idle(f);
                               return f.sys.steps_taken();
                             })
      .def_property_readonly("nominal_radius",
                             [](const PyFloaters& f) {
                               idle(f);
                               return f.sys.nominal_radius();
                             })
      .def_property_readonly("last_step",
                             [](const PyFloaters& f) {
                               idle(f);
                               return step_dict(f.last);
                             })
      .def_property_readonly("surface",
                             [](const PyFloaters& f) {
                               idle(f);
                               return PySurface{Scene{f.sys.surface()}, f.sys.surface().label()};
                             })
      .def(
          "save",
          [](const PyFloaters& f, const std::string& path, bool ascii) {
            idle(f);
            if (file_extension(path) != "ply")
              throw InvalidArgument("path", path,
                                    "the point set is written as PLY: use a .ply name");
            write_points_ply(path, f.sys.positions(), f.sys.normals(), f.sys.radii(),
                             ascii ? PlyFormat::kAscii : PlyFormat::kBinaryLittleEndian);
          },
          "path"_a, "ascii"_a = false)
      .def(
          "render",
          [](PyFloaters& f, int width, int height, std::optional<std::vector<double>> camera,
             double disk_scale, bool show_singular, int threads) {
            const Busy busy(f);  // drawn without the GIL
            // As `zeroset sample --png`.
            if (!(disk_scale > 0) || !std::isfinite(disk_scale))
              throw InvalidArgument("disk_scale", std::to_string(disk_scale), "must be positive");
            validate_image_size(width, height);
            const Surface& surface = f.sys.surface();
            Camera cam = surface.camera;
            if (camera) {
              if (camera->size() < 2 || camera->size() > 3)
                throw InvalidArgument("camera", "", "expected (azimuth, elevation[, distance])");
              cam.azimuth_deg = (*camera)[0];
              cam.elevation_deg = (*camera)[1];
              if (camera->size() == 3) cam.distance = (*camera)[2];
              validate_camera(cam);
            }
            RenderOptions ro;
            ro.width = width;
            ro.height = height;
            ro.threads = threads;
            std::vector<double> disks(f.sys.radii().begin(), f.sys.radii().end());
            for (double& r : disks) r *= disk_scale;
            ro.camera = cam.aimed_at(f.sys.positions(), 1e-9 * surface.scene_radius());
            Image image;
            run_interruptible([&](std::stop_token stop) {
              if (show_singular && surface.clip.is_bounded())
                ro.singular_overlay = SingularOverlay{.set = find_singular_set(surface, {}, stop)};
              if (!stop.stop_requested())
                image = render_points(surface, f.sys.positions(), f.sys.normals(), disks, ro);
            });
            return to_array(image);
          },
          "width"_a, "height"_a, "camera"_a, "disk_scale"_a, "show_singular"_a, "threads"_a);

  m.def("_sample", &sample, "surface"_a, "options"_a, "steps"_a, "max_steps"_a, "animate"_a,
        "settle_steps"_a, "quality"_a, "threads"_a);
  m.def("_floaters", [](const PySurface& s, const std::string& given, int threads) {
    return PyFloaters{FloaterSystem(s.surface(), options_from(s, given, threads)), {}, false};
  });
}

}  // namespace zeroset::python
