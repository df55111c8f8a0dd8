// Surface.mesh: the steps of `zeroset mesh` (apps/cli/cmd_mesh.cpp) in the same order with the
// same options: polygonize, crossings, the improver until at rest or its step limit, finish.
#include <chrono>
#include <optional>

#include "bindings.h"
#include "zeroset/error.h"
#include "zeroset/mesh/adjacency.h"
#include "zeroset/mesh/crossings.h"
#include "zeroset/mesh/carry.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/remesh.h"
#include "zeroset/mesh/mesh_io.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"
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

// As `zeroset mesh`: the scene file's "mesh" object, then the arguments given.
MeshSettings settings_from(const MeshArgs& a, const PySurface& s) {
  MeshSettings m;
  if (s.scene.settings.contains("mesh"))
    apply_mesh_settings(s.scene.settings["mesh"], m, "'" + s.spec + "'");
  if (a.resolution) m.cells = *a.resolution;
  if (a.improve) apply_improve(*a.improve, m);
  if (a.boundary) m.boundary = parse_boundary(*a.boundary);
  if (a.improver) m.improver = parse_improver(*a.improver);
  if (a.grid) m.grid = parse_grid(*a.grid);
  if (a.refine_steps) m.refine_steps = *a.refine_steps;
  if (a.curvature_weight) m.curvature_weight = *a.curvature_weight;
  for (auto [given, setting] :
       {std::pair{&a.curvature, &m.curvature}, std::pair{&a.singularity, &m.singularity},
        std::pair{&a.flips, &m.flips}, std::pair{&a.find_singular, &m.find_singular},
        std::pair{&a.crossings, &m.crossings}, std::pair{&a.curves, &m.curves}})
    if (*given) *setting = **given;
  validate_settings(m);
  // As `zeroset mesh` refuses their flags: the paper's own settings (kPaperOnlyMeshKeys) do
  // nothing with the remesher, so one given explicitly is refused rather than ignored.
  if (m.improver == Improver::kRemesh)
    for (auto [given, name] : {std::pair{a.curvature.has_value(), "curvature"},
                               std::pair{a.curvature_weight.has_value(), "curvature_weight"},
                               std::pair{a.singularity.has_value(), "singularity"},
                               std::pair{a.flips.has_value(), "flips"}})
      if (given)
        throw InvalidArgument(std::string(name) +
                              " sets the paper's improver, but the improver is remesh: add "
                              "improver=\"paper\"");
  return m;
}

py::dict polygonize_dict(const PolygonizeStats& ps, int resolution, const Mesh& mesh) {
  return py::dict("resolution"_a = resolution, "cells"_a = ps.cells, "cell_size"_a = ps.cell_size,
                  "grid"_a = ps.sparse ? "sparse" : "dense", "bricks"_a = ps.bricks,
                  "bricks_kept"_a = ps.bricks_kept, "grid_samples"_a = ps.grid_samples,
                  "refine_evaluations"_a = ps.refine_evaluations, "nan_samples"_a = ps.nan_samples,
                  "active_cells"_a = ps.active_cells, "ambiguous_faces"_a = ps.ambiguous_faces,
                  "edge_vertices"_a = ps.edge_vertices, "collapsed_edges"_a = ps.collapsed_edges,
                  "clip_cut_edges"_a = ps.clip_cut_edges,
                  "clip_snapped_vertices"_a = ps.clip_snapped, "seconds"_a = ps.seconds_total,
                  "vertices"_a = mesh.vertex_count(), "triangles"_a = mesh.triangle_count());
}

py::dict crossings_dict(const CrossingStats& cs) {
  return py::dict("crossing_curves"_a = cs.crossing_curves,
                  "isolated_curves"_a = cs.isolated_curves, "curve_vertices"_a = cs.curve_vertices,
                  "removed_triangles"_a = cs.removed_triangles,
                  "added_triangles"_a = cs.added_triangles, "strip_vertices"_a = cs.strip_vertices,
                  "failure"_a = cs.failure, "seconds"_a = cs.seconds);
}

py::dict improve_dict(const ImproveStats& is, int max_steps) {
  std::vector<Vec3> found = is.singular_points;
  return py::dict(
      "steps"_a = is.steps, "max_steps"_a = max_steps, "converged"_a = is.converged,
      "last_max_move_in_mean_edges"_a = is.max_move, "edge_flips"_a = is.flips,
      "shortened_moves"_a = is.shortened_moves, "cancelled_moves"_a = is.cancelled_moves,
      "flipped_triangles"_a = is.flipped_triangles, "singular_points_found"_a = to_array(found),
      "max_residual"_a = is.max_residual, "seconds"_a = is.seconds);
}

py::dict quality_dict(const MeshQuality& q, const MeshTopology& t) {
  return py::dict(
      "vertices"_a = q.vertices, "triangles"_a = q.triangles,
      "mean_edge_length"_a = q.mean_edge_length, "min_angle_histogram"_a = q.min_angle_histogram,
      "percent_min_angle_below_10"_a = q.percent_below_10,
      "percent_min_angle_below_20"_a = q.percent_below_20,
      "percent_min_angle_below_30"_a = q.percent_below_30,
      "mean_min_angle_deg"_a = q.mean_min_angle_deg, "smallest_angle_deg"_a = q.smallest_angle_deg,
      "mean_radius_ratio"_a = q.mean_radius_ratio, "max_residual"_a = q.max_residual,
      "rms_residual"_a = q.rms_residual, "max_normal_deviation_deg"_a = q.max_normal_deviation_deg,
      "flipped_triangles"_a = q.flipped_triangles, "boundary_vertices"_a = q.boundary_vertices,
      "edges"_a = t.edges, "boundary_edges"_a = t.boundary_edges,
      "non_manifold_edges"_a = t.non_manifold_edges,
      "euler_characteristic"_a = t.euler_characteristic, "watertight"_a = t.is_watertight());
}

py::tuple make_mesh(const PySurface& s, const MeshArgs& a) {
  // Its own copy: another Python thread may change the surface while the GIL is released.
  const Surface surface = s.surface();
  const MeshSettings settings = settings_from(a, s);
  PolygonizeOptions po = polygonize_options(settings);
  po.threads = a.threads;
  ImproveOptions io = improve_options(settings, ImproveOptions{}.max_steps);
  io.threads = a.threads;
  const int max_steps = io.max_steps;
  check_grid_memory(surface, po, "resolution");

  Mesh mesh;
  PolygonizeStats ps;
  std::optional<CrossingStats> cs;
  std::optional<SingularSet> singular;  // the crossings', for the remesher too
  ImproveStats is;
  RemeshStats rs;
  std::optional<MeshQuality> before, after;
  std::optional<MeshTopology> topology_before, topology_after;
  double seconds = 0;
  QualityOptions qo;
  qo.threads = a.threads;
  run_interruptible([&](std::stop_token stop) {
    const auto t0 = std::chrono::steady_clock::now();
    mesh = polygonize(surface, po, &ps, stop);
    if (settings.crossings && !mesh.empty() && !stop.stop_requested())
      cs = mesh_crossings(mesh, surface, ps.cell_size, {}, &singular.emplace(), stop);
    if (a.quality) {
      before = measure_quality(mesh, surface, qo);
      topology_before = mesh_topology(mesh);
    }
    if (max_steps > 0 && !mesh.empty() && !stop.stop_requested() &&
        settings.improver == Improver::kRemesh) {
      RemeshOptions ro = remesh_options(settings);
      ro.threads = a.threads;
      if (singular) ro.singular_set = &*singular;
      rs = remesh(mesh, surface, ro, stop);
      if (stop.stop_requested()) return;
    } else if (max_steps > 0 && !mesh.empty() && !stop.stop_requested()) {
      MeshImprover improver(std::move(mesh), surface, io);
      for (int k = 0; k < max_steps && !improver.converged(); ++k) {
        if (stop.stop_requested()) return;
        improver.step();
      }
      improver.finish();
      is = improver.stats();
      mesh = improver.take_mesh();
    }
    if (a.quality) {
      after = measure_quality(mesh, surface, qo);
      topology_after = mesh_topology(mesh);
    }
    if (!settings.curves) mesh.curves.clear();
    seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  });

  py::dict stats;
  stats["surface"] = surface.label();
  stats["polygonize"] = polygonize_dict(ps, settings.cells, mesh);
  if (cs) stats["crossings"] = crossings_dict(*cs);
  if (max_steps > 0 && settings.improver == Improver::kRemesh) {
    stats["improve"] = py::dict(
        "improver"_a = "remesh", "iterations"_a = rs.iterations, "converged"_a = rs.converged,
        "target_edge"_a = rs.target_edge, "splits"_a = rs.splits, "collapses"_a = rs.collapses,
        "flips"_a = rs.flips, "relax_steps"_a = rs.relax_steps,
        "pinch_held_vertices"_a = rs.pinch_held_vertices,
        "pinch_improver_steps"_a = rs.pinch_improver_steps,
        "max_residual"_a = rs.max_residual, "seconds"_a = rs.seconds,
        "boundary"_a = std::string(to_string(settings.boundary)));
  } else if (max_steps > 0) {
    py::dict d = improve_dict(is, max_steps);
    d["improver"] = "paper";
    d["boundary"] = std::string(to_string(settings.boundary));
    stats["improve"] = d;
  }
  if (before) stats["quality_before"] = quality_dict(*before, *topology_before);
  if (after) stats["quality_after"] = quality_dict(*after, *topology_after);
  stats["seconds_total"] = seconds;
  return py::make_tuple(PyMesh{std::move(mesh), surface}, stats);
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

  m.def("_mesh", [](const PySurface& s, std::optional<int> resolution,
                    std::optional<std::string> improve, std::optional<std::string> boundary,
                    std::optional<std::string> grid, std::optional<int> refine_steps,
                    std::optional<bool> curvature, std::optional<double> curvature_weight,
                    std::optional<bool> singularity, std::optional<bool> flips,
                    std::optional<bool> find_singular, std::optional<bool> crossings,
                    std::optional<bool> curves, std::optional<std::string> improver,
                    bool quality, int threads) {
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
        run_interruptible(
            [&](std::stop_token stop) { r = carry_mesh(p.mesh, p.surface, target, options, stop); });
        py::dict stats("carried"_a = r.carried(), "failure"_a = std::string(to_string(r.failure)),
                       "reason"_a = r.reason, "seconds"_a = r.seconds,
                       "max_move_edges"_a = r.max_move_edges, "max_residual"_a = r.max_residual,
                       "smallest_angle_deg"_a = r.smallest_angle_deg,
                       "flipped_triangles"_a = r.flipped_triangles,
                       "node_vertices"_a = r.node_vertices);
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
