// zeroset mesh: marching cubes cut at the clip, isotropic remeshing or the spring–mass improver
// of Rösch, Ruhl & Saupe (§4), mesh files, a picture and quality figures.
#include <fmt/core.h>

#include <chrono>
#include <cmath>
#include <optional>

#include "common.h"
#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/io/image.h"
#include "zeroset/io/output_transaction.h"
#include "zeroset/mesh/adjacency.h"
#include "zeroset/mesh/crossings.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/mesh_io.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"
#include "zeroset/mesh/remesh.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/render/render.h"
#include "zeroset/surface/json_read.h"

namespace zeroset::cli {
namespace {

struct MeshArgs {
  SurfaceArgs surface;
  int resolution = 128;
  std::string grid = "auto";
  int refine_steps = PolygonizeOptions{}.refine_steps;
  std::string improve = "auto";
  std::string boundary = "constrain";
  std::string improver = "remesh";
  bool no_curvature = false;
  bool no_singularity = false;
  bool no_flips = false;
  bool no_find_singular = false;
  bool no_crossings = false;
  bool no_curves = false;
  std::string output;
  std::string stats;
  std::string png;
  std::string png_raw;
  std::string size = "500x500";
  bool wireframe = false;
  bool show_singular = false;

  CLI::Option* resolution_opt = nullptr;
  CLI::Option* improve_opt = nullptr;
  CLI::Option* boundary_opt = nullptr;
  CLI::Option* improver_opt = nullptr;
  CLI::Option* grid_opt = nullptr;
  CLI::Option* refine_steps_opt = nullptr;
  CLI::Option* curvature_weight_opt = nullptr;
  double curvature_weight = MeshSettings{}.curvature_weight;
};

// The flags of the paper's own settings (kPaperOnlyMeshKeys). With the remesher they would do
// nothing, so one given explicitly is refused rather than ignored.
void refuse_paper_only_flags(const MeshArgs& a, const MeshSettings& m) {
  const std::pair<bool, const char*> flags[] = {
      {a.no_curvature, "--no-curvature"},
      {a.curvature_weight_opt->count() > 0, "--curvature-weight"},
      {a.no_singularity, "--no-singularity"},
      {a.no_flips, "--no-flips"}};
  static_assert(std::size(flags) == kPaperOnlyMeshKeys.size());
  if (m.improver != Improver::kRemesh) return;
  for (const auto& [given, flag] : flags)
    if (given)
      throw InvalidArgument(fmt::format("{} sets the paper's improver, but the improver is "
                                        "remesh: add --improver paper",
                                        flag));
}

// Settings from a scene file's "mesh" object (as the viewer saves them, or with improve as
// --improve takes it); flags given explicitly win. The scene's values are checked as it is
// read, the flags' here, by the same validator.
MeshSettings settings_from(const MeshArgs& a, const Scene& scene) {
  MeshSettings m;
  m.cells = a.resolution;
  if (scene.settings.contains("mesh"))
    apply_mesh_settings(scene.settings["mesh"], m, "'" + a.surface.spec + "'");
  validate_flags(
      [&] {
        if (a.resolution_opt->count()) m.cells = a.resolution;
        if (a.improve_opt->count()) apply_improve(a.improve, m);
        if (a.boundary_opt->count()) m.boundary = parse_boundary(a.boundary);
        if (a.improver_opt->count()) m.improver = parse_improver(a.improver);
        if (a.grid_opt->count()) m.grid = parse_grid(a.grid);
        if (a.refine_steps_opt->count()) m.refine_steps = a.refine_steps;
        if (a.curvature_weight_opt->count()) m.curvature_weight = a.curvature_weight;
        // The switches turn off what the scene may have on.
        if (a.no_curvature) m.curvature = false;
        if (a.no_singularity) m.singularity = false;
        if (a.no_flips) m.flips = false;
        if (a.no_find_singular) m.find_singular = false;
        if (a.no_crossings) m.crossings = false;
        if (a.no_curves) m.curves = false;
        validate_settings(m);
      },
      {{"cells", "--resolution"},
       {"improve", "--improve"},
       {"boundary", "--boundary"},
       {"improver", "--improver"},
       {"grid", "--grid"},
       {"refine_steps", "--refine-steps"},
       {"curvature_weight", "--curvature-weight"}});
  refuse_paper_only_flags(a, m);
  return m;
}

nlohmann::json quality_json(const MeshQuality& q) {
  nlohmann::json j;
  j["vertices"] = q.vertices;
  j["triangles"] = q.triangles;
  j["mean_edge_length"] = q.mean_edge_length;
  j["min_angle_histogram"] = {{"bin_width_deg", 5}, {"counts", q.min_angle_histogram}};
  j["percent_min_angle_below_10"] = q.percent_below_10;
  j["percent_min_angle_below_20"] = q.percent_below_20;
  j["percent_min_angle_below_30"] = q.percent_below_30;
  j["mean_min_angle_deg"] = q.mean_min_angle_deg;
  j["smallest_angle_deg"] = q.smallest_angle_deg;
  j["zero_area_triangles"] = q.zero_area_triangles;
  j["coincident_vertices"] = q.coincident_vertices;
  j["radius_ratio"] = {{"mean", q.mean_radius_ratio}, {"min", q.min_radius_ratio}};
  j["residual"] = {{"max", q.max_residual},
                   {"rms", q.rms_residual},
                   {"vertices", q.residual_vertices},
                   {"undefined_vertices", q.undefined_vertices},
                   {"excluded_radius_around_singular_points", q.singular_radius}};
  j["normal_deviation_deg"] = {{"mean", q.mean_normal_deviation_deg},
                               {"max", q.max_normal_deviation_deg},
                               {"flipped_triangles", q.flipped_triangles}};
  j["boundary"] = {{"vertices", q.boundary_vertices}, {"max_abs_clip_value", q.max_boundary_clip_value}};
  nlohmann::json sing = nlohmann::json::array();
  for (size_t k = 0; k < q.singular_points.size(); ++k)
    sing.push_back({{"point", json_read::from_vec3(q.singular_points[k])},
                    {"nearest_vertex_distance", q.singular_point_distance[k]},
                    {"in_mean_edge_lengths", q.mean_edge_length > 0 ? q.singular_point_distance[k] / q.mean_edge_length : 0.0}});
  j["singular_points"] = sing;
  return j;
}

nlohmann::json topology_json(const Mesh& m) {
  const MeshTopology t = mesh_topology(m);
  return {{"vertices", t.vertices},
          {"edges", t.edges},
          {"triangles", t.triangles},
          {"boundary_edges", t.boundary_edges},
          {"non_manifold_edges", t.non_manifold_edges},
          {"misoriented_edges", t.misoriented_edges},
          {"euler_characteristic", t.euler_characteristic},
          {"watertight", t.is_watertight()}};
}

void write_picture(const Surface& surface, const Mesh& mesh, const std::string& path, int width,
                   int height, bool wireframe, const SingularSet* singular) {
  RenderOptions ro;
  ro.width = width;
  ro.height = height;
  ro.samples = 2;
  ro.threads = global_flags().threads;
  if (singular) ro.singular_overlay = SingularOverlay{.set = *singular};
  write_png(render_mesh(surface, mesh, ro, wireframe), path);
}

void run_mesh(const MeshArgs& a) {
  if (a.output.empty() && a.png.empty() && a.png_raw.empty() && a.stats.empty())
    throw InvalidArgument(
        "nothing to write: give -o FILE.{obj,ply,stl,glb}, --png FILE.png or --stats FILE.json");
  if (!a.output.empty()) check_mesh_path(a.output);
  for (const auto& [flag, path] : {std::pair{"--png", a.png}, std::pair{"--png-raw", a.png_raw}})
    if (!path.empty() && file_extension(path) != "png") throw InvalidArgument(flag, path, "use a .png name");
  if (!a.stats.empty() && file_extension(a.stats) != "json")
    throw InvalidArgument("--stats", a.stats, "use a .json name");
  const auto [width, height] = parse_size(a.size, "--size");
  OutputTransaction outputs;  // every file or none (docs/architecture.md, "Errors")
  for (const auto& [flag, path] : {std::pair{"--output", a.output}, std::pair{"--png-raw", a.png_raw},
                                   std::pair{"--png", a.png}, std::pair{"--stats", a.stats}})
    if (!path.empty()) outputs.declare(path, flag);

  Scene scene = a.surface.resolve();
  const Surface& surface = scene.surface;

  const MeshSettings settings = settings_from(a, scene);
  const int resolution = settings.cells;

  PolygonizeOptions po = polygonize_options(settings);
  po.threads = global_flags().threads;
  ImproveOptions io = improve_options(settings, ImproveOptions{}.max_steps);
  io.threads = global_flags().threads;
  const int max_steps = io.max_steps;
  check_grid_memory(surface, po, "--resolution");

  const FieldSurvey survey = survey_and_warn(surface);
  const auto t0 = std::chrono::steady_clock::now();
  PolygonizeStats ps;
  Mesh mesh = polygonize(surface, po, &ps);
  nlohmann::json stats;
  stats["surface"] = surface.label();
  nlohmann::json params = nlohmann::json::object();
  const auto& names = surface.field.parameter_names();
  for (size_t k = 0; k < names.size(); ++k) params[names[k]] = surface.field.parameter_values()[k];
  stats["parameters"] = params;
  stats["clip"] = surface.clip.to_specs();
  stats["field"] = survey_json(survey);
  stats["polygonize"] = {
      {"resolution", resolution},
      {"cells", ps.cells},
      {"cell_size", ps.cell_size},
      {"grid", ps.sparse ? "sparse" : "dense"},
      {"bricks", ps.bricks},
      {"bricks_kept", ps.bricks_kept},
      {"grid_samples", ps.grid_samples},
      {"refine_evaluations", ps.refine_evaluations},
      {"nan_samples", ps.nan_samples},
      {"undefined_edges", ps.undefined_edges},
      {"pole_edges", ps.pole_edges},
      {"undefined_triangles", ps.undefined_triangles},
      {"active_cells", ps.active_cells},
      {"ambiguous_faces", ps.ambiguous_faces},
      {"edge_vertices", ps.edge_vertices},
      {"welded_vertices", ps.welded_vertices},
      {"collapsed_edges", ps.collapsed_edges},
      {"clip_cut_edges", ps.clip_cut_edges},
      {"clip_snapped_vertices", ps.clip_snapped},
      {"seconds", {{"sampling", ps.seconds_sampling},
                   {"extraction", ps.seconds_extraction},
                   {"refinement", ps.seconds_refinement},
                   {"cleanup", ps.seconds_cleanup},
                   {"total", ps.seconds_total}}},
      {"vertices", mesh.vertex_count()},
      {"triangles", mesh.triangle_count()}};
  if (mesh.empty() && !survey.vanishes_identically())  // that was said
    say(fmt::format("{}: the grid of {} cells found no surface inside the clip", surface.label(), resolution));
  // One search of the singular set serves the crossings, the warning about a singular sheet,
  // --stats and --show-singular: the crossings' (traced at the mesh's edge length) when they
  // run, else one of its own for --stats and --show-singular (milliseconds, next to the
  // mesh's seconds).
  std::optional<SingularSet> singular;
  std::optional<CrossingStats> crossings;
  if (settings.crossings && !mesh.empty() && ps.cell_size > 0) {
    SingularSet found;
    crossings = mesh_crossings(mesh, surface, ps.cell_size, {}, &found);
    singular = std::move(found);
  } else if (a.show_singular || !a.stats.empty()) {
    singular = singular_set_if_bounded(surface);
  }
  const SingularSet* overlay = a.show_singular && singular ? &*singular : nullptr;
  stats["singular_set"] = singular_stats(singular);
  // F ≡ 0 was warned about; its "sheet" of vanishing ∇F is the whole clip, nothing to add.
  if (!survey.vanishes_identically()) warn_if_singular_sheet(surface, singular);
  if (crossings) {
    const CrossingStats& cs = *crossings;
    stats["crossings"] = {{"crossing_curves", cs.crossing_curves},
                          {"isolated_curves", cs.isolated_curves},
                          {"curve_vertices", cs.curve_vertices},
                          {"removed_triangles", cs.removed_triangles},
                          {"added_triangles", cs.added_triangles},
                          {"strip_vertices", cs.strip_vertices},
                          {"failure", cs.failure},
                          {"seconds", cs.seconds}};
    if (!cs.failure.empty())
      warn(fmt::format("{}: the crossings along its singular curves are left as marching cubes "
                       "made them (rounded off): {}", surface.label(), cs.failure));
  }
  const bool want_quality = !a.stats.empty();
  QualityOptions qo;
  qo.threads = po.threads;
  std::optional<MeshQuality> before;
  if (want_quality) {
    before = measure_quality(mesh, surface, qo);
    stats["quality_before"] = quality_json(*before);
    stats["topology_before"] = topology_json(mesh);
  }
  if (!a.png_raw.empty())
    write_picture(surface, mesh, a.png_raw, width, height, a.wireframe, overlay);

  ImproveStats is;
  RemeshStats rs;
  const bool remeshing = settings.improver == Improver::kRemesh;
  if (max_steps > 0 && !mesh.empty() && remeshing) {
    RemeshOptions ro = remesh_options(settings);
    ro.threads = global_flags().threads;
    if (singular) ro.singular_set = &*singular;  // found once, for the crossings or --stats
    rs = remesh(mesh, surface, ro);
    is.steps = rs.iterations, is.converged = rs.converged, is.seconds = rs.seconds;
    is.undefined_vertices = rs.undefined_vertices;
    nlohmann::json held = nlohmann::json::array();
    for (const Vec3& p : rs.singular_points) held.push_back(json_read::from_vec3(p));
    stats["improve"] = {{"improver", "remesh"},
                        {"iterations", rs.iterations},
                        {"max_iterations", ro.max_iterations},
                        {"converged", rs.converged},
                        {"target_edge", rs.target_edge},
                        {"splits", rs.splits},
                        {"collapses", rs.collapses},
                        {"flips", rs.flips},
                        {"refused_collapses", rs.refused_collapses},
                        {"relax_steps", rs.relax_steps},
                        {"reverted_moves", rs.reverted_moves},
                        {"last_max_move_in_target_edges", rs.last_max_move},
                        {"singular_points_held", held},
                        {"missed_singular_points", rs.missed_singular_points},
                        {"pinch_held_vertices", rs.pinch_held_vertices},
                        {"pinch_improver_steps", rs.pinch_improver_steps},
                        {"max_residual", rs.max_residual},
                        {"undefined_vertices", rs.undefined_vertices},
                        {"boundary", std::string(to_string(settings.boundary))},
                        {"find_singular_points", ro.find_singular_points},
                        {"seconds", rs.seconds}};
  } else if (max_steps > 0 && !mesh.empty()) {
    Progress progress("improving", global_flags().quiet);
    MeshImprover improver(std::move(mesh), surface, io);
    for (int k = 0; k < max_steps && !improver.converged(); ++k) {
      improver.step();
      progress.update(static_cast<double>(k + 1) / max_steps);
    }
    improver.finish();
    progress.finish();
    is = improver.stats();
    mesh = improver.take_mesh();
    nlohmann::json found = nlohmann::json::array();
    for (const Vec3& p : is.singular_points) found.push_back(json_read::from_vec3(p));
    stats["improve"] = {{"improver", "paper"},
                        {"steps", is.steps},
                        {"max_steps", max_steps},
                        {"converged", is.converged},
                        {"last_max_move_in_mean_edges", is.max_move},
                        {"edge_flips", is.flips},
                        {"shortened_moves", is.shortened_moves},
                        {"cancelled_moves", is.cancelled_moves},
                        {"flipped_triangles", is.flipped_triangles},
                        {"singular_points_found", found},
                        {"max_residual", is.max_residual},
                        {"refused_moves", is.refused_moves},
                        {"undefined_vertices", is.undefined_vertices},
                        {"boundary", std::string(to_string(settings.boundary))},
                        {"curvature", io.use_curvature},
                        {"curvature_weight", io.curvature_weight},
                        {"singularity", io.use_singularity},
                        {"flips", io.flip_edges},
                        {"find_singular_points", io.find_singular_points},
                        {"seconds", is.seconds}};
  }
  std::optional<MeshQuality> after;
  if (want_quality) {
    after = measure_quality(mesh, surface, qo);
    stats["quality_after"] = quality_json(*after);
    stats["topology_after"] = topology_json(mesh);
  }
  if (!settings.curves) mesh.curves.clear();
  // The mesher never makes degenerate output (a test sweeps for it); if it ever did, say so.
  if (const DegenerateCount d = count_degenerate(mesh); d.zero_area_triangles + d.coincident_vertices > 0)
    warn(fmt::format("{}: the mesh has {} triangles of zero area and {} vertices on top of "
                     "others; please report this surface and these options",
                     surface.label(), d.zero_area_triangles, d.coincident_vertices));
  // The polygonizer and the improver keep vertices where F is finite; if one ever is not, say so.
  if (const long long undefined = after ? static_cast<long long>(after->undefined_vertices)
                                        : is.undefined_vertices;
      undefined > 0)
    warn(fmt::format("{}: {} vertices lie where F is undefined (NaN or infinite); please "
                     "report this surface and these options",
                     surface.label(), undefined));
  if (!a.output.empty()) write_mesh(mesh, a.output);
  if (!a.png.empty())
    write_picture(surface, mesh, a.png, width, height, a.wireframe, overlay);
  stats["seconds_total"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!a.stats.empty()) write_json(stats, a.stats);
  outputs.commit();

  std::string line = fmt::format("{}: {} vertices, {} triangles ({} grid, {} cells, {:.2f} s)",
                                 surface.label(), mesh.vertex_count(), mesh.triangle_count(),
                                 ps.sparse ? "sparse" : "dense", resolution, ps.seconds_total);
  if (max_steps > 0)
    line += fmt::format("; {} in {} {} ({:.2f} s{})", remeshing ? "remeshed" : "improved",
                        is.steps, remeshing ? "iterations" : "steps", is.seconds,
                        is.converged || mesh.empty() ? ""
                                                     : ", stopped at the step limit, not at rest");
  say(line);
  if (before && after)
    say(fmt::format("  min angle < 30°: {:.1f}% -> {:.1f}%, mean min angle {:.1f}° -> {:.1f}°, "
                    "max residual {:.1e}",
                    before->percent_below_30, after->percent_below_30, before->mean_min_angle_deg,
                    after->mean_min_angle_deg, after->max_residual));
  for (const auto& path : {a.output, a.png_raw, a.png, a.stats})
    if (!path.empty()) say("  wrote " + path);
}

}  // namespace

void register_mesh_command(CLI::App& app) {
  auto args = std::make_shared<MeshArgs>();
  CLI::App* cmd = app.add_subcommand(
      "mesh",
      "Polygonize a surface (marching cubes cut at the clip) and improve the mesh by isotropic "
      "remeshing, or with the spring-mass system of Rosch, Ruhl & Saupe (1997, section 4) "
      "given --improver paper.\n\n"
      "Examples:\n"
      "  zeroset mesh kummer --param mu=1.5 -o kummer.obj\n"
      "  zeroset mesh kummer --param mu=1.2 --resolution 48 --png-raw raw.png --png improved.png "
      "--wireframe\n"
      "  zeroset mesh kummer --param mu=1.5 --improver paper --no-flips -o paper.obj\n"
      "  zeroset mesh torus --improve off --stats torus.json -o torus.glb");
  args->surface.add_to(cmd);
  args->resolution_opt =
      cmd->add_option("-r,--resolution", args->resolution,
                      "Grid cells along the longest side of the clip's bounding box")
          ->capture_default_str();
  args->grid_opt =
      cmd->add_option("--grid", args->grid,
                      "auto, dense (sample every node) or sparse (bricks near the surface only)")
          ->type_name("auto|dense|sparse")
          ->capture_default_str();
  args->refine_steps_opt =
      cmd->add_option("--refine-steps", args->refine_steps,
                      fmt::format("Steps placing each vertex onto F = 0 along its grid edge, one "
                                  "evaluation of F each (0: linear interpolation, as classic "
                                  "marching cubes; at most {})",
                                  kMaxRefineSteps))
          ->capture_default_str();
  args->improve_opt =
      cmd->add_option("--improve", args->improve,
                      "auto (until at rest), off, or at most STEPS steps (the remesher's "
                      "iterations or the paper improver's steps)")
          ->type_name("auto|off|STEPS")
          ->capture_default_str();
  args->improver_opt =
      cmd->add_option("--improver", args->improver,
                      "remesh: isotropic remeshing (split, collapse, flip, relax) with singular "
                      "points, singular curves and the clip curve kept exactly; paper: the "
                      "spring-mass improver of the paper, with the flags of its own group below")
          ->type_name("remesh|paper")
          ->capture_default_str();
  args->boundary_opt =
      cmd->add_option("--boundary", args->boundary,
                      "Boundary vertices: fix, or constrain to the clip curve F = 0, G = 0")
          ->type_name("fix|constrain")
          ->capture_default_str();
  // The paper improver's own flags, in a group of their own in --help (refused with the
  // remesher, refuse_paper_only_flags).
  const std::string paper_only = "Paper improver only (--improver paper)";
  cmd->add_flag("--no-curvature", args->no_curvature,
                "Springs without the curvature estimator (paper eq. 6)")
      ->group(paper_only);
  args->curvature_weight_opt =
      cmd->add_option("--curvature-weight", args->curvature_weight,
                      fmt::format("kappa_d, the weight of the curvature estimator in the spring "
                                  "lengths (0 to {:g})",
                                  kMaxCurvatureWeight))
          ->capture_default_str()
          ->group(paper_only);
  cmd->add_flag("--no-singularity", args->no_singularity,
                "Springs without the singularity estimator")
      ->group(paper_only);
  cmd->add_flag("--no-flips", args->no_flips, "No Delaunay edge flips (vertex motion only)")
      ->group(paper_only);
  cmd->add_flag("--no-find-singular", args->no_find_singular,
                "Do not search singular points by Newton's method on grad F = 0");
  cmd->add_flag("--no-crossings", args->no_crossings,
                "Leave crossings along singular curves as marching cubes makes them (sheets "
                "rounded off a cell away from the curve) instead of meeting exactly on it");
  cmd->add_flag("--no-curves", args->no_curves,
                "Leave the singular curves out of the mesh file (OBJ 'l' lines, PLY edges)");
  cmd->add_option("-o,--output", args->output, "Mesh file: .obj, .ply, .stl or .glb")
      ->type_name("FILE");
  cmd->add_option("--stats", args->stats,
                  "JSON file with counts, timings, quality before and after improvement and the "
                  "singular set found")
      ->type_name("FILE.json");
  cmd->add_option("--png", args->png, "Picture of the final mesh")->type_name("FILE.png");
  cmd->add_option("--png-raw", args->png_raw, "Picture of the polygonizer's mesh before improvement")
      ->type_name("FILE.png");
  cmd->add_option("--size", args->size, "Picture size WxH")->capture_default_str();
  cmd->add_flag("--wireframe", args->wireframe, "Draw the mesh edges in the pictures");
  add_show_singular_flag(cmd, args->show_singular, "the pictures (--png, --png-raw)");
  cmd->callback([args] { run_mesh(*args); });
}

}  // namespace zeroset::cli
