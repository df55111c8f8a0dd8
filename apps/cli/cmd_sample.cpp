// zeroset sample: floaters on a surface (Witkin–Heckbert with the Rösch–Ruhl–Saupe
// extensions), written as a PLY point set, a picture and quality figures.
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <optional>

#include "common.h"
#include "zeroset/error.h"
#include "zeroset/floaters/ply.h"
#include "zeroset/floaters/sample_surface.h"
#include "zeroset/floaters/settings.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/io/image.h"
#include "zeroset/io/output_transaction.h"
#include "zeroset/render/render.h"

namespace zeroset::cli {
namespace {

struct SampleArgs {
  SurfaceArgs surface;
  double radius = 0;
  std::size_t max_count = 0;
  std::size_t seed_count = 0;
  std::size_t steps = 0;
  bool until_converged = false;
  std::size_t max_steps = 3000;
  std::uint64_t seed = 1;
  bool no_cos_weight = false;
  bool no_clip_projection = false;
  bool no_snap = false;
  bool plain_repulsion = false;
  bool no_clip_newton = false;
  bool no_average_mu = false;
  bool no_local_radius = false;
  bool no_taper = false;
  bool no_fission_offset = false;
  double grading = 0;
  double feedback = 0;
  double equilibrium_speed = 0;
  int estimator_interval = 0;
  std::string radius_adapt;
  std::string animate;
  std::size_t settle_steps = 1000;
  std::string output;
  bool ascii = false;
  std::string stats;
  std::string png;
  bool show_singular = false;
  std::string size = "500x500";
  std::string camera;
  double disk_scale = 0.75;
  double band = 0;
  std::size_t reference = 20000;

  CLI::Option* radius_opt = nullptr;
  CLI::Option* max_count_opt = nullptr;
  CLI::Option* seed_count_opt = nullptr;
  CLI::Option* seed_opt = nullptr;
  CLI::Option* steps_opt = nullptr;
  CLI::Option* grading_opt = nullptr;
  CLI::Option* feedback_opt = nullptr;
  CLI::Option* equilibrium_speed_opt = nullptr;
  CLI::Option* estimator_interval_opt = nullptr;
};

// Each floater setting's flag (a key of the scene file's "floaters" object).
const FlagNames kFloaterFlags = {{"radius", "--radius"},
                                 {"max_count", "--max-count"},
                                 {"seed_count", "--seed-count"},
                                 {"seed", "--seed"},
                                 {"cos_weight", "--no-cos-weight"},
                                 {"clip_projection", "--no-clip-projection"},
                                 {"snap_to_nodes", "--no-snap"},
                                 {"scaled_repulsion", "--plain-repulsion"},
                                 {"clip_newton", "--no-clip-newton"},
                                 {"average_radius_factor", "--no-average-mu"},
                                 {"local_nominal_radius", "--no-local-radius"},
                                 {"energy_taper", "--no-taper"},
                                 {"fission_offset", "--no-fission-offset"},
                                 {"radius_grading", "--grading"},
                                 {"feedback", "--feedback"},
                                 {"equilibrium_speed", "--equilibrium-speed"},
                                 {"estimator_interval", "--estimator-interval"},
                                 {"radius_adapt", "--radius-adapt"}};

// Settings from a scene file's "floaters" object, then the flags given, as the same keys
// through the same reader (apply_floater_options): a bad value gets the same words, named by
// its flag.
FloaterOptions options_from(const SampleArgs& a, const Scene& scene) {
  FloaterOptions o;
  if (scene.settings.contains("floaters"))
    apply_floater_settings(scene.settings["floaters"], o, "'" + a.surface.spec + "'");
  nlohmann::json given = nlohmann::json::object();
  if (a.radius_opt->count()) given["radius"] = a.radius;
  if (a.max_count_opt->count()) given["max_count"] = a.max_count;
  if (a.seed_count_opt->count()) given["seed_count"] = a.seed_count;
  if (a.seed_opt->count()) given["seed"] = a.seed;
  if (a.grading_opt->count()) given["radius_grading"] = a.grading;
  if (a.feedback_opt->count()) given["feedback"] = a.feedback;
  if (a.equilibrium_speed_opt->count()) given["equilibrium_speed"] = a.equilibrium_speed;
  if (a.estimator_interval_opt->count()) given["estimator_interval"] = a.estimator_interval;
  if (!a.radius_adapt.empty()) given["radius_adapt"] = a.radius_adapt;
  // The switches turn off what the scene may have on.
  for (const auto& [off, key] :
       {std::pair{a.no_cos_weight, "cos_weight"},
        std::pair{a.no_clip_projection, "clip_projection"}, std::pair{a.no_snap, "snap_to_nodes"},
        std::pair{a.plain_repulsion, "scaled_repulsion"},
        std::pair{a.no_clip_newton, "clip_newton"},
        std::pair{a.no_average_mu, "average_radius_factor"},
        std::pair{a.no_local_radius, "local_nominal_radius"}, std::pair{a.no_taper, "energy_taper"},
        std::pair{a.no_fission_offset, "fission_offset"}})
    if (off) given[key] = false;
  validate_flags([&] { apply_floater_options(given, o); }, kFloaterFlags);
  o.threads = global_flags().threads;
  check_floater_memory(o, o.seed_count > o.max_count ? "--seed-count" : "--max-count");
  return o;
}

// The outputs of a run that has no surface to sample (F vanishes identically): a point set
// without points and its (empty) picture.
void write_empty_sample(const SampleArgs& a, const Surface& surface, const Camera& camera,
                        int width, int height) {
  if (!a.output.empty())
    write_points_ply(a.output, {}, {}, {},
                     a.ascii ? PlyFormat::kAscii : PlyFormat::kBinaryLittleEndian);
  if (!a.png.empty()) {
    RenderOptions ro;
    ro.width = width;
    ro.height = height;
    ro.threads = global_flags().threads;
    ro.camera = camera;
    write_png(render_points(surface, {}, {}, {}, ro), a.png);
  }
}

void run_sample(const SampleArgs& a) {
  if (a.output.empty() && a.png.empty() && a.stats.empty())
    throw InvalidArgument(
        "nothing to write: give -o FILE.ply, --png FILE.png or --stats FILE.json");
  if (!a.output.empty() && file_extension(a.output) != "ply")
    throw InvalidArgument("-o", a.output, "the point set is written as PLY: use a .ply name");
  if (!a.png.empty() && file_extension(a.png) != "png")
    throw InvalidArgument("--png", a.png, "use a .png name");
  if (!a.stats.empty() && file_extension(a.stats) != "json")
    throw InvalidArgument("--stats", a.stats, "use a .json name");
  if (!(a.disk_scale > 0) || !std::isfinite(a.disk_scale))
    throw InvalidArgument("--disk-scale", fmt::format("{}", a.disk_scale), "must be positive");
  check_flag_range("--disk-scale", a.disk_scale, 0, 100);
  check_flag_range("--band", a.band, 0, kMaxFloaterRadius);
  check_flag_range("--steps", static_cast<double>(a.steps), 0, kMaxFloaterSteps);
  check_flag_range("--max-steps", static_cast<double>(a.max_steps), 0, kMaxFloaterSteps);
  check_flag_range("--settle-steps", static_cast<double>(a.settle_steps), 0, kMaxFloaterSteps);
  const auto [width, height] = parse_size(a.size, "--size");
  std::optional<ParamRange> anim;
  if (!a.animate.empty()) {
    anim = parse_range(a.animate, "--animate");
    if (a.steps == 0)
      throw InvalidArgument("--animate", a.animate,
                            "give the number of animated steps with --steps N");
  }
  OutputTransaction outputs;  // every file or none (docs/architecture.md, "Errors")
  for (const auto& [flag, path] :
       {std::pair{"--output", a.output}, std::pair{"--png", a.png}, std::pair{"--stats", a.stats}})
    if (!path.empty()) outputs.declare(path, flag);

  Scene scene = a.surface.resolve();
  const Surface& surface = scene.surface;
  if (anim && surface.field.parameter_index(anim->name) < 0)
    throw InvalidArgument("--animate", a.animate,
                          fmt::format("{} has no parameter '{}'", surface.label(), anim->name));
  const FloaterOptions options = options_from(a, scene);
  const Camera camera = with_camera_flag(surface.camera, a.camera);

  SampleRun run;
  if (a.steps_opt->count() && !anim) run.steps = a.steps;
  run.max_steps = a.max_steps;
  if (anim)
    run.animation = SampleAnimation{.parameter = anim->name,
                                    .from = anim->from,
                                    .to = anim->to,
                                    .steps = a.steps,
                                    .settle_steps = a.settle_steps};
  if (!a.stats.empty()) {
    MetricsOptions mo;
    mo.band_halfwidth = a.band;  // 0: half the nominal radius
    mo.reference.count = a.reference;
    run.metrics = mo;
  }
  run.singular_set = a.show_singular;
  run.on_warning = warn;
  Progress progress("sampling", global_flags().quiet);
  run.on_step = [&](const StepStats&, double done) { progress.update(done); };
  const SampleResult result = sample_surface(surface, options, run);
  progress.finish();
  if (!result.system) {
    write_empty_sample(a, result.surface, camera, width, height);
    if (!a.stats.empty()) write_json(result.to_json(), a.stats);
    outputs.commit();
    say(fmt::format("{}: 0 floaters (no surface)", result.surface.label()));
    return;
  }
  const FloaterSystem& sys = *result.system;
  if (!a.output.empty())
    write_points_ply(a.output, sys.positions(), sys.normals(), sys.radii(),
                     a.ascii ? PlyFormat::kAscii : PlyFormat::kBinaryLittleEndian);
  if (!a.png.empty()) {
    RenderOptions ro;
    ro.width = width;
    ro.height = height;
    ro.threads = global_flags().threads;
    std::vector<double> disks(sys.radii().begin(), sys.radii().end());
    for (double& r : disks) r *= a.disk_scale;
    ro.camera = camera.aimed_at(sys.positions(), 1e-9 * result.surface.scene_radius());
    if (a.show_singular && result.singular)
      ro.singular_overlay = SingularOverlay{.set = *result.singular};
    write_png(render_points(result.surface, sys.positions(), sys.normals(), disks, ro), a.png);
  }
  if (!a.stats.empty()) write_json(result.to_json(), a.stats);
  outputs.commit();
  const double seconds = result.seconds;
  say(fmt::format(
      "{} floaters after {} steps ({}), sigma^ = {:.4g}, {:.0f} steps/s", sys.size(),
      sys.steps_taken(),
      result.converged_at ? fmt::format("settled at step {}", *result.converged_at) : "not settled",
      sys.nominal_radius(), seconds > 0 ? static_cast<double>(sys.steps_taken()) / seconds : 0.0));
}

}  // namespace

void register_sample_command(CLI::App& app) {
  auto a = std::make_shared<SampleArgs>();
  auto* cmd = app.add_subcommand(
      "sample",
      "Sample a surface with floaters: particles that repel each other and stay on F = 0\n"
      "(Witkin-Heckbert 1994 with the extensions of Rosch-Ruhl-Saupe 1997: clip projection,\n"
      "cosine-weighted repulsion, smaller floaters near singular points and strong curvature).\n"
      "Writes the floaters as PLY (position, normal, radius), a picture of them as shaded\n"
      "disks, and quality figures.\n\n"
      "Examples:\n"
      "  zeroset sample kummer --param mu=1.5 -o kummer.ply --png kummer.png\n"
      "  zeroset sample cone --camera 30,55 --png cone.png --stats cone.json  # figure 3(b)\n"
      "  zeroset sample planes --no-cos-weight --radius-adapt wh --plain-repulsion \\\n"
      "      --png gap.png                  # the original method: figure 4(d)\n"
      "  zeroset sample kummer --radius-adapt wh --max-count 500 --steps 400 -o wh.ply\n"
      "  zeroset sample kummer --animate mu=1.02:2.44 --steps 500 --stats anim.json\n"
      "  zeroset sample \"x^2 + y^2 = z^2\" --clip sphere:1 --radius 0.05 -o cone.ply");
  a->surface.add_to(cmd);
  a->radius_opt =
      cmd->add_option("--radius", a->radius,
                      "Nominal floater radius sigma^ (the density knob; spacing is "
                      "about 1.5 sigma^). Default (or 0): from the surface's area so that "
                      "about max-count/3 floaters would cover it uniformly. "
                      "Kept within [1e-9, 1] times the scene radius")
          ->type_name("LENGTH");
  a->max_count_opt = cmd->add_option("--max-count", a->max_count,
                                     "Population cap (default 2000, at most 100000000)");
  a->seed_count_opt = cmd->add_option("--seed-count", a->seed_count,
                                      "Random floaters inserted at the start (default 200)");
  a->steps_opt = cmd->add_option("--steps", a->steps,
                                 "Run exactly N steps (with --animate: N animated steps)");
  auto* until = cmd->add_flag("--until-converged", a->until_converged,
                              "Stop when the system has settled (the default), at most "
                              "--max-steps steps");
  until->excludes(a->steps_opt);
  cmd->add_option("--max-steps", a->max_steps, "Step limit for --until-converged")
      ->capture_default_str();
  a->seed_opt = cmd->add_option("--seed", a->seed, "Random seed (same seed, same floaters)");
  cmd->add_flag("--no-cos-weight", a->no_cos_weight,
                "Plain repulsion: no |cos| weighting between sheets (paper figure 4(d))");
  cmd->add_flag("--no-clip-projection", a->no_clip_projection,
                "Remove floaters that leave the clip volume instead of projecting them back");
  cmd->add_flag(
      "--no-snap", a->no_snap,
      "Do not hold floaters on the singular set: on nodes they come near, on pinch, triple and "
      "other special points, and along singular curves");
  cmd->add_flag("--plain-repulsion", a->plain_repulsion,
                "Witkin-Heckbert's desired velocity exactly, instead of pair forces scaled by "
                "the pair's mean radius (with it a graded density never settles)");
  a->grading_opt = cmd->add_option("--grading", a->grading,
                                   "How fast the fission radius may grow with distance from a "
                                   "neighbour's (default 0.1; 0: off)");
  // zeroset's heuristics beyond the papers, each with the plain rule as its "off".
  cmd->add_flag("--no-clip-newton", a->no_clip_newton,
                "After projecting a floater back into the clip volume, do not step it along the "
                "boundary onto F = 0 (the paper's projection alone)");
  cmd->add_flag("--no-average-mu", a->no_average_mu,
                "Take each refresh of the radius factor mu alone instead of averaging it with "
                "the previous one");
  cmd->add_flag("--no-local-radius", a->no_local_radius,
                "Fission and death compare with the nominal radius sigma^ (the paper) instead of "
                "the local min(sigma^, fission radius)");
  cmd->add_flag("--no-taper", a->no_taper,
                "Witkin-Heckbert's plain Gaussian energy (cut off at 3 sigma) instead of the "
                "one tapered to zero there");
  cmd->add_flag("--no-fission-offset", a->no_fission_offset,
                "A fission child starts where its parent is (Witkin-Heckbert) instead of at a "
                "random offset of 0.25 to 0.5 radii");
  a->feedback_opt = cmd->add_option("--feedback", a->feedback,
                                    "phi, the pull towards F = 0 (default 15; below 2/dt = 66.7)");
  a->equilibrium_speed_opt =
      cmd->add_option("--equilibrium-speed", a->equilibrium_speed,
                      "gamma: a floater slower than gamma radii per time unit may fission or die "
                      "(default 4; in (0, 16.7])");
  a->estimator_interval_opt =
      cmd->add_option("--estimator-interval", a->estimator_interval,
                      "Refresh the curvature and singularity estimators every N steps (default "
                      "8; 1 to 1000)");
  cmd->add_option("--radius-adapt", a->radius_adapt,
                  "Per-floater fission radius: wh (global, original method), curvature, "
                  "singular or mixed (default, alpha/3 + 2 beta/3)");
  cmd->add_option("--animate", a->animate,
                  "Move a parameter while sampling, e.g. mu=1.02:2.44 (after settling at the "
                  "start value; needs --steps)")
      ->type_name("NAME=FROM:TO");
  cmd->add_option("--settle-steps", a->settle_steps,
                  "With --animate: at most this many steps to settle first")
      ->capture_default_str();
  cmd->add_option("-o,--output", a->output, "Floaters as PLY (binary little-endian)")
      ->type_name("FILE.ply");
  cmd->add_flag("--ascii", a->ascii, "Write the PLY as ASCII");
  cmd->add_option("--stats", a->stats,
                  "Quality figures as JSON: count, steps/s, residual, spacing CV, covering "
                  "radius, singular point coverage, density near the singular set, the singular "
                  "set found")
      ->type_name("FILE.json");
  cmd->add_option("--png", a->png, "Picture of the floaters as shaded disks")
      ->type_name("FILE.png");
  add_show_singular_flag(cmd, a->show_singular, "the --png picture");
  cmd->add_option("--camera", a->camera,
                  "Orbit camera AZIMUTH,ELEVATION[,DISTANCE[,ROLL]] in degrees (z up) for --png; "
                  "without a distance the picture is framed on the floaters")
      ->type_name("AZ,EL[,D[,R]]");
  cmd->add_option("--size", a->size, "Picture size")->capture_default_str()->type_name("WxH");
  cmd->add_option("--disk-scale", a->disk_scale, "Disk radius in the picture per floater radius")
      ->capture_default_str();
  cmd->add_option("--band", a->band,
                  "Half width of the band around the singular set for the density figure "
                  "(default sigma^/2)");
  cmd->add_option("--reference", a->reference,
                  "Reference points on the surface for the covering radius")
      ->capture_default_str()
      ->check(CLI::Range(std::size_t{100}, std::size_t{10'000'000}));
  cmd->callback([a] { run_sample(*a); });
}

}  // namespace zeroset::cli
