// The mesh recipe of every front end (zeroset/mesh/mesh_surface.h, docs/meshing.md "The
// pipeline"): survey, marching cubes, crossings, improvement, checks.
#include "zeroset/mesh/mesh_surface.h"

#include <fmt/core.h>

#include <chrono>
#include <utility>

namespace zeroset {
namespace {

// A warning goes to the front end as it arises and stays in the result.
void say_warning(MeshResult& result, const MeshRun& run, std::string line) {
  if (run.on_warning) run.on_warning(line);
  result.warnings.push_back(std::move(line));
}

// The crossings step finds the singular set (traced at the mesh's edge length) and serves the
// remesher, the warning about a singular sheet and the stats; without it, a search of its own
// when the front end asks (milliseconds, next to the mesh's seconds).
void find_crossings(MeshResult& r, const MeshRun& run, std::stop_token stop) {
  if (r.settings.crossings && !r.mesh.empty() && r.polygonize.cell_size > 0) {
    SingularSet found;
    r.crossings = mesh_crossings(r.mesh, r.surface, r.polygonize.cell_size, {}, &found, stop);
    r.singular = std::move(found);
    if (const auto& left = r.crossings->left_as_marching_cubes; !left.empty())
      say_warning(r, run,
                  fmt::format("{}: the crossings near ({:.4g}, {:.4g}, {:.4g}){} could not be "
                              "joined to their curves and are left as marching cubes made them "
                              "(rounded off there); every other crossing is treated",
                              r.surface.label(), left[0].at.x(), left[0].at.y(), left[0].at.z(),
                              left.size() > 1 ? fmt::format(" and {} more place{}", left.size() - 1,
                                                            left.size() > 2 ? "s" : "")
                                              : std::string()));
    if (!r.crossings->failure.empty())
      say_warning(r, run,
                  fmt::format("{}: the crossings along its singular curves are left as marching "
                              "cubes made them (rounded off): {}",
                              r.surface.label(), r.crossings->failure));
  } else if (run.singular_set) {
    r.singular = find_singular_set_if_bounded(r.surface, stop);
  }
  // F ≡ 0 was warned about; its "sheet" of vanishing ∇F is the whole clip, nothing to add.
  if (run.survey && !r.survey->vanishes_identically())
    if (auto line = singular_sheet_warning(r.surface, r.singular ? &*r.singular : nullptr))
      say_warning(r, run, std::move(*line));
}

// The checks every finished mesh gets: the mesher never makes degenerate output and keeps
// vertices where F is finite (tests sweep for both); if it ever does not, say so.
void check_result(MeshResult& r, const MeshRun& run) {
  if (const DegenerateCount d = count_degenerate(r.mesh);
      d.zero_area_triangles + d.coincident_vertices > 0)
    say_warning(r, run,
                fmt::format("{}: the mesh has {} triangles of zero area and {} vertices on top "
                            "of others; please report this surface and these options",
                            r.surface.label(), d.zero_area_triangles, d.coincident_vertices));
  const long long undefined = r.quality_after
                                  ? static_cast<long long>(r.quality_after->undefined_vertices)
                              : r.improvement ? r.improvement->summary().undefined_vertices
                                              : 0;
  if (undefined > 0)
    say_warning(r, run,
                fmt::format("{}: {} vertices lie where F is undefined (NaN or infinite); please "
                            "report this surface and these options",
                            r.surface.label(), undefined));
}

}  // namespace

ImproveStats MeshImprovement::summary() const {
  if (improver == Improver::kPaper) return paper;
  ImproveStats s;
  s.steps = remesh.iterations;
  s.converged = remesh.converged;
  s.seconds = remesh.seconds;
  s.max_residual = remesh.max_residual;
  s.undefined_vertices = remesh.undefined_vertices;
  s.singular_points = remesh.singular_points;
  return s;
}

std::optional<MeshImprovement> improve_surface_mesh(Mesh& mesh, const Surface& surface,
                                                    const MeshSettings& settings,
                                                    const MeshRun& run, const SingularSet* known,
                                                    int steps_done, std::stop_token stop) {
  ImproveOptions io = improve_options(settings, run.auto_steps);
  io.threads = run.threads;
  const int limit = io.max_steps - steps_done;
  if (limit <= 0 || mesh.empty() || stop.stop_requested()) return std::nullopt;
  MeshImprovement m;
  m.improver = settings.improver;
  m.boundary = settings.boundary;
  if (settings.improver == Improver::kRemesh) {
    m.remesh_options = remesh_options(settings);
    m.remesh_options.threads = run.threads;
    m.remesh_options.singular_set = known;  // found once, for the crossings or the stats
    m.remesh = remesh(mesh, surface, m.remesh_options, stop);
    m.remesh_options.singular_set = nullptr;  // borrowed for the call only
    if (stop.stop_requested()) return std::nullopt;
    return m;
  }
  m.paper_options = io;
  MeshImprover improver(std::move(mesh), surface, io);
  bool finished = false;
  for (int k = 1; k <= limit && !stop.stop_requested(); ++k) {
    improver.step();
    finished = improver.converged() || k == limit;
    if (finished) improver.finish();
    if (run.on_improver_step) run.on_improver_step(improver, steps_done + k, finished);
    if (finished) break;
  }
  m.paper = improver.stats();
  mesh = improver.take_mesh();
  if (!finished) return std::nullopt;
  return m;
}

MeshResult mesh_surface(const Surface& surface, const MeshSettings& settings, const MeshRun& run,
                        std::stop_token stop) {
  validate_settings(settings);
  MeshResult r;
  r.surface = surface;
  r.settings = settings;
  PolygonizeOptions po = polygonize_options(settings);
  po.threads = run.threads;
  check_grid_memory(surface, po, run.cells_option);
  if (run.survey) {
    r.survey = survey_field(surface);
    if (auto line = survey_warning(surface, *r.survey)) say_warning(r, run, std::move(*line));
  }
  const auto t0 = std::chrono::steady_clock::now();
  auto finish = [&] {
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.stopped = stop.stop_requested();
    return std::move(r);
  };
  r.mesh = polygonize(surface, po, &r.polygonize, stop);
  r.polygonized_vertices = r.mesh.vertex_count();
  r.polygonized_triangles = r.mesh.triangle_count();
  if (stop.stop_requested()) return finish();
  find_crossings(r, run, stop);
  if (stop.stop_requested()) return finish();
  QualityOptions qo;
  qo.threads = run.threads;
  if (run.quality) {
    r.quality_before = measure_quality(r.mesh, surface, qo);
    r.topology_before = mesh_topology(r.mesh);
  }
  if (run.on_polygonized) run.on_polygonized(r);
  r.improvement = improve_surface_mesh(r.mesh, surface, settings, run,
                                       r.singular ? &*r.singular : nullptr, 0, stop);
  if (stop.stop_requested()) return finish();
  if (run.quality) {
    r.quality_after = measure_quality(r.mesh, surface, qo);
    r.topology_after = mesh_topology(r.mesh);
  }
  if (!settings.curves) r.mesh.curves.clear();
  check_result(r, run);
  return finish();
}

}  // namespace zeroset
