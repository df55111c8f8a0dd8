// zeroset mesh: marching cubes cut at the clip, isotropic remeshing or the spring–mass improver
// of Rösch, Ruhl & Saupe (§4), mesh files, a picture and quality figures.
#include <fmt/core.h>

#include <optional>

#include "common.h"
#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/io/image.h"
#include "zeroset/io/output_transaction.h"
#include "zeroset/mesh/mesh_io.h"
#include "zeroset/mesh/mesh_surface.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/render/render.h"

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

// Each mesh setting's flag (a key of the scene file's "mesh" object, docs/meshing.md).
const FlagNames kMeshFlags = {{"cells", "--resolution"},
                              {"improve", "--improve"},
                              {"boundary", "--boundary"},
                              {"improver", "--improver"},
                              {"grid", "--grid"},
                              {"refine_steps", "--refine-steps"},
                              {"curvature_weight", "--curvature-weight"},
                              {"curvature", "--no-curvature"},
                              {"singularity", "--no-singularity"},
                              {"flips", "--no-flips"},
                              {"find_singular", "--no-find-singular"},
                              {"crossings", "--no-crossings"},
                              {"curves", "--no-curves"}};

// Settings from a scene file's "mesh" object (as the viewer saves them, or with improve as
// --improve takes it), then the flags given, as the same keys through the same reader
// (apply_mesh_options): a bad value gets the same words, named by its flag.
MeshSettings settings_from(const MeshArgs& a, const Scene& scene) {
  MeshSettings m;
  if (scene.settings.contains("mesh"))
    apply_mesh_settings(scene.settings["mesh"], m, "'" + a.surface.spec + "'");
  nlohmann::json given = nlohmann::json::object();
  if (a.resolution_opt->count()) given["cells"] = a.resolution;
  if (a.improve_opt->count()) given["improve"] = a.improve;
  if (a.boundary_opt->count()) given["boundary"] = a.boundary;
  if (a.improver_opt->count()) given["improver"] = a.improver;
  if (a.grid_opt->count()) given["grid"] = a.grid;
  if (a.refine_steps_opt->count()) given["refine_steps"] = a.refine_steps;
  if (a.curvature_weight_opt->count()) given["curvature_weight"] = a.curvature_weight;
  // The switches turn off what the scene may have on.
  for (const auto& [off, key] :
       {std::pair{a.no_curvature, "curvature"}, std::pair{a.no_singularity, "singularity"},
        std::pair{a.no_flips, "flips"}, std::pair{a.no_find_singular, "find_singular"},
        std::pair{a.no_crossings, "crossings"}, std::pair{a.no_curves, "curves"}})
    if (off) given[key] = false;
  validate_flags(
      [&] {
        try {
          apply_mesh_options(given, m);
        } catch (const SettingError& e) {
          // The paper's own settings would do nothing with the remesher: say how to choose it.
          if (e.why() != kPaperOnlyRefusal) throw;
          throw InvalidArgument(flag_name(kMeshFlags, e.key()) + " " + e.why() +
                                ": add --improver paper");
        }
      },
      kMeshFlags);
  return m;
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
    if (!path.empty() && file_extension(path) != "png")
      throw InvalidArgument(flag, path, "use a .png name");
  if (!a.stats.empty() && file_extension(a.stats) != "json")
    throw InvalidArgument("--stats", a.stats, "use a .json name");
  const std::pair<int, int> size = parse_size(a.size, "--size");
  const int width = size.first, height = size.second;  // not a binding: a lambda uses them
  OutputTransaction outputs;  // every file or none (docs/architecture.md, "Errors")
  for (const auto& [flag, path] :
       {std::pair{"--output", a.output}, std::pair{"--png-raw", a.png_raw},
        std::pair{"--png", a.png}, std::pair{"--stats", a.stats}})
    if (!path.empty()) outputs.declare(path, flag);

  Scene scene = a.surface.resolve();
  const Surface& surface = scene.surface;
  const MeshSettings settings = settings_from(a, scene);

  MeshRun run;
  run.threads = global_flags().threads;
  run.quality = !a.stats.empty();
  run.singular_set = a.show_singular || !a.stats.empty();
  run.cells_option = "--resolution";
  run.on_warning = warn;
  run.on_polygonized = [&](const MeshResult& r) {
    if (r.mesh.empty() && !r.survey->vanishes_identically())  // that was said
      say(fmt::format("{}: the grid of {} cells found no surface inside the clip", surface.label(),
                      settings.cells));
    if (!a.png_raw.empty())
      write_picture(surface, r.mesh, a.png_raw, width, height, a.wireframe,
                    a.show_singular && r.singular ? &*r.singular : nullptr);
  };
  const int max_steps = improve_options(settings, run.auto_steps).max_steps;
  Progress progress("improving", global_flags().quiet);
  run.on_improver_step = [&](const MeshImprover&, int steps, bool done) {
    progress.update(static_cast<double>(steps) / max_steps);
    if (done) progress.finish();
  };
  const MeshResult result = mesh_surface(surface, settings, run);
  const Mesh& mesh = result.mesh;
  if (!a.output.empty()) write_mesh(mesh, a.output);
  if (!a.png.empty())
    write_picture(surface, mesh, a.png, width, height, a.wireframe,
                  a.show_singular && result.singular ? &*result.singular : nullptr);
  if (!a.stats.empty()) write_json(result.to_json(), a.stats);
  outputs.commit();

  const PolygonizeStats& ps = result.polygonize;
  const ImproveStats is = result.improvement ? result.improvement->summary() : ImproveStats{};
  const bool remeshing = settings.improver == Improver::kRemesh;
  const auto& before = result.quality_before;
  const auto& after = result.quality_after;
  std::string line = fmt::format("{}: {} vertices, {} triangles ({} grid, {} cells, {:.2f} s)",
                                 surface.label(), mesh.vertex_count(), mesh.triangle_count(),
                                 ps.sparse ? "sparse" : "dense", settings.cells, ps.seconds_total);
  if (max_steps > 0)
    line +=
        fmt::format("; {} in {} {} ({:.2f} s{})", remeshing ? "remeshed" : "improved", is.steps,
                    remeshing ? "iterations" : "steps", is.seconds,
                    is.converged || mesh.empty() ? "" : ", stopped at the step limit, not at rest");
  say(line);
  if (before && after)
    say(
        fmt::format("  min angle < 30°: {:.1f}% -> {:.1f}%, mean min angle {:.1f}° -> {:.1f}°, "
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
  // remesher, apply_mesh_options).
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
  cmd->add_option("--png-raw", args->png_raw,
                  "Picture of the polygonizer's mesh before improvement")
      ->type_name("FILE.png");
  cmd->add_option("--size", args->size, "Picture size WxH")->capture_default_str();
  cmd->add_flag("--wireframe", args->wireframe, "Draw the mesh edges in the pictures");
  add_show_singular_flag(cmd, args->show_singular, "the pictures (--png, --png-raw)");
  cmd->callback([args] { run_mesh(*args); });
}

}  // namespace zeroset::cli
