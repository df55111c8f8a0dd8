// Surface.mesh and the Mesh class: `zeroset mesh` (mesh_surface) from Python, mesh files,
// pictures and carrying.
#include <nlohmann/json.hpp>
#include <optional>

#include "bindings.h"
#include "zeroset/error.h"
#include "zeroset/mesh/carry.h"
#include "zeroset/mesh/mesh_io.h"
#include "zeroset/mesh/mesh_surface.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/render/render.h"

namespace zeroset::python {
namespace {

using namespace pybind11::literals;

/// A mesh with the surface it was made from (for pictures: camera, scene size, ∇F normals).
struct PyMesh {
  Mesh mesh;
  Surface surface;
};

struct MeshArgs {
  std::optional<int> resolution;
  std::optional<std::string> improve;  // "auto", "off" or a number of steps
  std::optional<std::string> boundary;
  std::optional<std::string> improver;  // "paper" or "remesh"
  std::optional<std::string> grid;
  std::optional<int> refine_steps;
  std::optional<bool> curvature, singularity, flips, find_singular, crossings, curves;
  std::optional<double> curvature_weight;
  bool quality = false;
  int threads = 0;
};

// As `zeroset mesh`: the scene file's "mesh" object, then the arguments given, as the same
// keys through the same reader (apply_mesh_options).
MeshSettings settings_from(const MeshArgs& a, const PySurface& s) {
  MeshSettings m;
  if (s.scene.settings.contains("mesh"))
    apply_mesh_settings(s.scene.settings["mesh"], m, "'" + s.spec + "'");
  nlohmann::json given = nlohmann::json::object();
  if (a.resolution) given["cells"] = *a.resolution;
  if (a.improve) given["improve"] = *a.improve;
  if (a.boundary) given["boundary"] = *a.boundary;
  if (a.improver) given["improver"] = *a.improver;
  if (a.grid) given["grid"] = *a.grid;
  if (a.refine_steps) given["refine_steps"] = *a.refine_steps;
  if (a.curvature_weight) given["curvature_weight"] = *a.curvature_weight;
  for (const auto& [value, key] :
       {std::pair{&a.curvature, "curvature"}, std::pair{&a.singularity, "singularity"},
        std::pair{&a.flips, "flips"}, std::pair{&a.find_singular, "find_singular"},
        std::pair{&a.crossings, "crossings"}, std::pair{&a.curves, "curves"}})
    if (*value) given[key] = **value;
  try {
    apply_mesh_options(given, m);
  } catch (const SettingError& e) {
    // The paper's own settings would do nothing with the remesher: say how to choose it.
    if (e.why() != kPaperOnlyRefusal) throw;
    throw InvalidArgument(e.key() + " " + e.why() + ": add improver=\"paper\"");
  }
  return m;
}

// The recipe of `zeroset mesh` (mesh_surface); the stats are its --stats file, as JSON text
// the module turns into dictionaries, and its warnings go to Python's warnings.
py::tuple make_mesh(const PySurface& s, const MeshArgs& a) {
  // Its own copy: another Python thread may change the surface while the GIL is released.
  const Surface surface = s.surface();
  const MeshSettings settings = settings_from(a, s);
  MeshRun run;
  run.threads = a.threads;
  run.quality = a.quality;
  run.singular_set = true;  // as `zeroset mesh --stats`
  run.cells_option = "resolution";
  std::optional<MeshResult> result;
  run_interruptible(
      [&](std::stop_token stop) { result = mesh_surface(surface, settings, run, stop); });
  Mesh mesh = std::move(result->mesh);
  return py::make_tuple(PyMesh{std::move(mesh), surface}, result->to_json().dump(),
                        result->warnings);
}

py::array_t<std::uint32_t> faces(const Mesh& m) {
  py::array_t<std::uint32_t> out({static_cast<py::ssize_t>(m.triangles.size()), py::ssize_t{3}});
  std::uint32_t* d = out.mutable_data();
  for (size_t i = 0; i < m.triangles.size(); ++i)
    for (int k = 0; k < 3; ++k) d[3 * i + k] = m.triangles[i][k];
  return out;
}

}  // namespace

void bind_mesh(py::module_& m) {
  py::class_<PyMesh>(m, "_Mesh")
      .def_property_readonly("vertices", [](const PyMesh& p) { return to_array(p.mesh.positions); })
      .def_property_readonly("faces", [](const PyMesh& p) { return faces(p.mesh); })
      .def_property_readonly("normals", [](const PyMesh& p) { return to_array(p.mesh.normals); })
      .def_property_readonly(
          "is_boundary",
          [](const PyMesh& p) {
            py::array_t<bool> out(static_cast<py::ssize_t>(p.mesh.is_boundary.size()));
            std::copy(p.mesh.is_boundary.begin(), p.mesh.is_boundary.end(), out.mutable_data());
            return out;
          })
      .def_property_readonly(
          "curves",
          [](const PyMesh& p) {
            py::list out;
            for (const MeshCurve& c : p.mesh.curves)
              out.append(
                  py::dict("kind"_a = std::string(to_string(c.kind)), "closed"_a = c.closed,
                           "vertices"_a = py::array_t<std::uint32_t>(
                               static_cast<py::ssize_t>(c.vertices.size()), c.vertices.data())));
            return out;
          })
      .def(
          "save", [](const PyMesh& p, const std::string& path) { write_mesh(p.mesh, path); },
          "path"_a)
      .def(
          "render",
          [](const PyMesh& p, int width, int height, bool wireframe, bool show_singular,
             int threads) {
            // As the pictures of `zeroset mesh --png`.
            RenderOptions ro;
            ro.width = width;
            ro.height = height;
            ro.samples = 2;
            ro.threads = threads;
            Image image;
            run_interruptible([&](std::stop_token stop) {
              if (show_singular && p.surface.clip.is_bounded())
                ro.singular_overlay =
                    SingularOverlay{.set = find_singular_set(p.surface, {}, stop)};
              if (!stop.stop_requested()) image = render_mesh(p.surface, p.mesh, ro, wireframe);
            });
            return to_array(image);
          },
          "width"_a, "height"_a, "wireframe"_a, "show_singular"_a, "threads"_a);

  m.def("_mesh",
        [](const PySurface& s, std::optional<int> resolution, std::optional<std::string> improve,
           std::optional<std::string> boundary, std::optional<std::string> grid,
           std::optional<int> refine_steps, std::optional<bool> curvature,
           std::optional<double> curvature_weight, std::optional<bool> singularity,
           std::optional<bool> flips, std::optional<bool> find_singular,
           std::optional<bool> crossings, std::optional<bool> curves,
           std::optional<std::string> improver, bool quality, int threads) {
          MeshArgs a{.resolution = resolution,
                     .improve = improve,
                     .boundary = boundary,
                     .improver = improver,
                     .grid = grid,
                     .refine_steps = refine_steps,
                     .curvature = curvature,
                     .singularity = singularity,
                     .flips = flips,
                     .find_singular = find_singular,
                     .crossings = crossings,
                     .curves = curves,
                     .curvature_weight = curvature_weight,
                     .quality = quality,
                     .threads = threads};
          return make_mesh(s, a);
        });
  // Carrying (docs/meshing.md, "Carrying a mesh"): the carried mesh, or None with the reason.
  m.def(
      "_carry",
      [](const PyMesh& p, const PySurface& to, int improve_steps, int threads) {
        const Surface target = to.surface();
        CarryOptions options;
        options.improve_steps = improve_steps, options.threads = threads;
        CarryResult r;
        run_interruptible([&](std::stop_token stop) {
          r = carry_mesh(p.mesh, p.surface, target, options, stop);
        });
        py::dict stats(
            "carried"_a = r.carried(), "failure"_a = std::string(to_string(r.failure)),
            "reason"_a = r.reason, "seconds"_a = r.seconds, "max_move_edges"_a = r.max_move_edges,
            "max_residual"_a = r.max_residual, "smallest_angle_deg"_a = r.smallest_angle_deg,
            "flipped_triangles"_a = r.flipped_triangles, "node_vertices"_a = r.node_vertices);
        py::object mesh = py::none();
        if (r.carried()) mesh = py::cast(PyMesh{std::move(r.mesh), target});
        return py::make_tuple(mesh, stats);
      },
      "mesh"_a, "to"_a, "improve_steps"_a, "threads"_a);
  m.def("_read_mesh", [](const std::string& path, const PySurface& s) {
    return PyMesh{read_mesh(path), s.surface()};
  });
}

}  // namespace zeroset::python
