// zeroset.Surface: resolving, parameters, the singular set, and batched field evaluation.
#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <thread>

#include "bindings.h"
#include "zeroset/error.h"
#include "zeroset/expr/field.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/settings.h"

namespace zeroset::python {
namespace {

using namespace pybind11::literals;

PySurface resolve(const std::string& spec, const std::map<std::string, double>& params,
                  const std::vector<std::string>& clip) {
  SurfaceOverrides o;
  o.params = params;
  o.clip_specs = clip;
  return PySurface{resolve_scene(spec, o), spec};
}

py::dict parameters(const Field& field) {
  py::dict d;
  for (size_t k = 0; k < field.parameter_names().size(); ++k)
    d[py::str(field.parameter_names()[k])] = field.parameter_values()[k];
  return d;
}

// Sets every value given or none: a copy of the field takes them first, so a bad name or value
// leaves the surface as it was.
void set_parameters(PySurface& s, const std::map<std::string, double>& values) {
  Field field = s.scene.surface.field;
  field.set_parameters(values);
  Clip clip = s.scene.surface.clip;
  clip.update(field);  // a clip that follows the parameters (docs/scenes.md)
  s.scene.surface.field = field;
  s.scene.surface.clip = std::move(clip);
}

py::dict camera_dict(const Camera& c) {
  return py::dict("azimuth_deg"_a = c.azimuth_deg, "elevation_deg"_a = c.elevation_deg,
                  "distance"_a = c.distance, "fov_deg"_a = c.fov_deg,
                  "projection"_a = projection_name(c.projection), "ortho_height"_a = c.ortho_height,
                  "target"_a = py::make_tuple(c.target.x(), c.target.y(), c.target.z()));
}

// --- batched evaluation --------------------------------------------------------------------
enum class What { kValue, kGradient, kHessian };
// Points per batch call: the structure-of-arrays buffers stay in cache (field_bench: 4,096).
constexpr size_t kChunk = 1024;

// Evaluates points [begin, end) with one Evaluator through the library's batch calls, copying
// each chunk into structure-of-arrays buffers and the results back into `out` (1, 3 or 9
// numbers per point).
void evaluate_range(const Field& field, const double* p, size_t begin, size_t end, What what,
                    double* out) {
  Evaluator ev(field);
  std::vector<double> x(kChunk), y(kChunk), z(kChunk), v(kChunk), gx(kChunk), gy(kChunk),
      gz(kChunk);
  std::array<std::vector<double>, 6> h;
  if (what == What::kHessian)
    for (auto& c : h) c.resize(kChunk);
  for (size_t b = begin; b < end; b += kChunk) {
    const size_t n = std::min(kChunk, end - b);
    const double* q = p + 3 * b;
    for (size_t i = 0; i < n; ++i) {
      x[i] = q[3 * i];
      y[i] = q[3 * i + 1];
      z[i] = q[3 * i + 2];
    }
    const std::span<const double> xs(x.data(), n), ys(y.data(), n), zs(z.data(), n);
    if (what == What::kValue) {
      ev.values(xs, ys, zs, std::span(out + b, n));
      continue;
    }
    const std::span<double> vs(v.data(), n), gxs(gx.data(), n), gys(gy.data(), n),
        gzs(gz.data(), n);
    if (what == What::kGradient) {
      ev.values_gradients(xs, ys, zs, vs, gxs, gys, gzs);
      double* o = out + 3 * b;
      for (size_t i = 0; i < n; ++i) {
        o[3 * i] = gx[i];
        o[3 * i + 1] = gy[i];
        o[3 * i + 2] = gz[i];
      }
      continue;
    }
    std::array<std::span<double>, 6> hs;
    for (int k = 0; k < 6; ++k) hs[k] = std::span(h[k].data(), n);
    ev.values_gradients_hessians(xs, ys, zs, vs, gxs, gys, gzs, hs);
    // Entries xx, xy, xz, yy, yz, zz into the symmetric 3×3 matrix, row-major.
    static constexpr int kEntry[9] = {0, 1, 2, 1, 3, 4, 2, 4, 5};
    double* o = out + 9 * b;
    for (size_t i = 0; i < n; ++i)
      for (int k = 0; k < 9; ++k) o[9 * i + k] = h[kEntry[k]][i];
  }
}

py::array_t<double> evaluate(const PySurface& s, const py::array_t<double, py::array::c_style>& pts,
                             What what, int threads) {
  const std::span<const double> p = points_of(pts);
  if (threads < 0) throw py::value_error("threads must be 0 (all cores) or positive");
  const size_t n = p.size() / 3;
  // A copy (the tape is shared): another Python thread may change the parameters meanwhile.
  const Field field = s.surface().field;
  field.require_parameters();  // before any work: a worker thread must not throw
  std::vector<py::ssize_t> shape{static_cast<py::ssize_t>(n)};
  if (what == What::kGradient) shape.push_back(3);
  if (what == What::kHessian) shape.insert(shape.end(), {3, 3});
  py::array_t<double> out(shape);
  double* o = out.mutable_data();
  const size_t cores = threads > 0 ? static_cast<size_t>(threads)
                                   : std::max(1u, std::thread::hardware_concurrency());
  // Ranges of at least 16 chunks each: a thread costs tens of microseconds to start.
  const size_t workers = std::clamp<size_t>(n / (16 * kChunk), 1, cores);
  py::gil_scoped_release release;
  if (workers == 1) {
    evaluate_range(field, p.data(), 0, n, what, o);
    return out;
  }
  std::vector<std::exception_ptr> errors(workers);
  {
    std::vector<std::jthread> pool;
    for (size_t w = 0; w < workers; ++w)
      pool.emplace_back([&, w] {
        try {
          evaluate_range(field, p.data(), n * w / workers, n * (w + 1) / workers, what, o);
        } catch (...) {  // out of memory: raised in the calling thread below
          errors[w] = std::current_exception();
        }
      });
  }
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  return out;
}

}  // namespace

void bind_surface(py::module_& m) {
  m.def("catalog", [] {
    py::list out;
    for (const CatalogEntry& e : catalog()) {
      py::dict params;
      for (const CatalogParam& p : e.params)
        params[py::str(p.name)] = py::dict("value"_a = p.value, "min"_a = p.min, "max"_a = p.max);
      out.append(py::dict("name"_a = e.name, "title"_a = e.title, "equation"_a = e.equation,
                          "description"_a = e.description, "params"_a = params,
                          "clip"_a = e.clip.to_specs()));
    }
    return out;
  });

  py::class_<PySurface>(m, "_Surface")
      .def(py::init(&resolve), "spec"_a, "params"_a, "clip"_a)
      .def("copy", [](const PySurface& s) { return s; })
      .def_property_readonly("spec", [](const PySurface& s) { return s.spec; })
      .def_property_readonly("name", [](const PySurface& s) { return s.surface().name; })
      .def_property_readonly("title", [](const PySurface& s) { return s.surface().title; })
      .def_property_readonly("label", [](const PySurface& s) { return s.surface().label(); })
      .def_property_readonly(
          "equation", [](const PySurface& s) { return s.surface().field.expression_string(); })
      .def_property_readonly("source",
                             [](const PySurface& s) { return s.surface().field.source(); })
      .def_property_readonly("degree",
                             [](const PySurface& s) { return s.surface().field.degree(); })
      .def_property_readonly("is_polynomial",
                             [](const PySurface& s) { return s.surface().field.is_polynomial(); })
      .def_property_readonly("clip", [](const PySurface& s) { return s.surface().clip.to_specs(); })
      .def_property_readonly("bounded",
                             [](const PySurface& s) { return s.surface().clip.is_bounded(); })
      .def_property_readonly("camera",
                             [](const PySurface& s) { return camera_dict(s.surface().camera); })
      .def("get_params", [](const PySurface& s) { return parameters(s.surface().field); })
      .def("param_names", [](const PySurface& s) { return s.surface().field.parameter_names(); })
      .def("param_ranges",
           [](const PySurface& s) {
             py::dict d;
             for (const ParamSpec& r : s.surface().ranges)
               d[py::str(r.name)] = py::make_tuple(r.min, r.max);
             return d;
           })
      .def("set_params", &set_parameters, "values"_a)
      .def("known_singular_points",
           [](const PySurface& s) { return to_array(s.surface().singular_points()); })
      .def(
          "singular_set",
          [](const PySurface& s, int cells) {
            SingularSet set;
            const Surface surface = s.surface();  // its own copy while the GIL is released
            run_interruptible([&](std::stop_token stop) {
              set = find_singular_set(surface, {.cells = cells}, stop);
            });
            return singular_set_dict(set);
          },
          "cells"_a = SingularSetOptions{}.cells)
      .def("scene_json", [](const PySurface& s) { return scene_to_json(s.scene).dump(2); })
      .def("save_scene",
           [](const PySurface& s, const std::string& path) { write_scene(s.scene, path); })
      .def(
          "eval",
          [](const PySurface& s, const py::array_t<double, py::array::c_style>& p, int threads) {
            return evaluate(s, p, What::kValue, threads);
          },
          "points"_a, "threads"_a = 0)
      .def(
          "grad",
          [](const PySurface& s, const py::array_t<double, py::array::c_style>& p, int threads) {
            return evaluate(s, p, What::kGradient, threads);
          },
          "points"_a, "threads"_a = 0)
      .def(
          "hessian",
          [](const PySurface& s, const py::array_t<double, py::array::c_style>& p, int threads) {
            return evaluate(s, p, What::kHessian, threads);
          },
          "points"_a, "threads"_a = 0);
}

}  // namespace zeroset::python
