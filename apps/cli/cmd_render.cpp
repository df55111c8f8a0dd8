// zeroset render | animate | export: pictures, animations and POV-Ray scenes of a surface.
#include <fmt/core.h>
#include <unistd.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <sstream>
#include <tuple>

#include "common.h"
#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/io/image.h"
#include "zeroset/io/output_transaction.h"
#include "zeroset/render/pov_export.h"
#include "zeroset/render/raycast.h"
#include "zeroset/render/render.h"
#include "zeroset/render/settings.h"
#include "zeroset/surface/jsurf.h"
#include "zeroset/surface/keyframes.h"
#include "zeroset/surface/settings.h"

namespace zeroset::cli {
namespace {

namespace fs = std::filesystem;

/// Flags shared by render, animate and export: how the picture looks.
struct LookArgs {
  std::string size = "800x800";
  int aa = 2;
  std::string camera;      // az,el[,dist]
  std::string projection;  // perspective | ortho[:height]
  std::string target;      // x,y,z
  double fov = 0;
  std::string background, front, back;
  CLI::Option* size_opt = nullptr;
  CLI::Option* fov_opt = nullptr;
  CLI::Option* aa_opt = nullptr;

  void add_to(CLI::App* cmd, bool with_aa = true) {
    size_opt = cmd->add_option("--size", size,
                               "Image size WIDTHxHEIGHT (default 800x800, or the scene file's)")
                   ->type_name("WxH");
    if (with_aa)
      aa_opt = cmd->add_option("--aa", aa,
                               "Anti-aliasing: N×N rays per pixel, 1 = none (default 2, or the "
                               "scene file's)");
    cmd->add_option("--camera", camera,
                    "Orbit camera AZIMUTH,ELEVATION[,DISTANCE[,ROLL]] in degrees (z up unless "
                    "ROLL turns the camera about its view direction); distance 0 or omitted "
                    "fits the clip volume")
        ->type_name("AZ,EL[,D[,R]]");
    cmd->add_option("--projection", projection,
                    "Camera projection: perspective, or ortho[:HEIGHT] for parallel rays "
                    "showing a window HEIGHT world units high (omitted: fits the clip "
                    "volume); default: the surface's (perspective unless its scene file says "
                    "otherwise)")
        ->type_name("perspective|ortho[:H]");
    cmd->add_option("--target", target,
                    "Point the camera orbits and looks at (default: the "
                    "surface's, usually the origin)")
        ->type_name("X,Y,Z");
    fov_opt = cmd->add_option("--fov", fov,
                              "Vertical field of view in degrees, 1 to 170 (default: the "
                              "surface's)");
    cmd->add_option("--background", background,
                    "Background colour: #rrggbb or r,g,b in [0,1] (default white)")
        ->type_name("COLOR");
    cmd->add_option("--front", front, "Colour of the side ∇F points to (default orange)")
        ->type_name("COLOR");
    cmd->add_option("--back", back, "Colour of the other side (default dark blue)")
        ->type_name("COLOR");
  }

  /// Render options for a scene: defaults, then the scene file's "render" object, then the
  /// flags given. Throws InvalidArgument naming the bad flag, BadInput for a bad scene entry.
  RenderOptions options(const Scene& scene, const std::string& origin) const {
    const Surface& surface = scene.surface;
    RenderOptions o;
    o.samples = 2;
    if (scene.settings.is_object() && scene.settings.contains("render"))
      apply_render_settings(scene.settings["render"], o, origin);
    if (size_opt && size_opt->count() > 0) std::tie(o.width, o.height) = parse_size(size, "--size");
    if (aa_opt && aa_opt->count() > 0) o.samples = aa;
    o.threads = global_flags().threads;
    Camera cam = with_projection_flag(with_camera_flag(surface.camera, camera), projection);
    if (!target.empty()) {
      const std::vector<double> v = parse_numbers(target, "--target");
      if (v.size() != 3) throw InvalidArgument("--target", target, "expected three numbers x,y,z");
      cam.target = Vec3(v[0], v[1], v[2]);
    }
    if (fov_opt && fov_opt->count() > 0) cam.fov_deg = fov;
    validate_flags([&] { validate_camera(cam); }, {{"azimuth_deg", "--camera azimuth"},
                                                   {"elevation_deg", "--camera elevation"},
                                                   {"distance", "--camera distance"},
                                                   {"fov_deg", "--fov"},
                                                   {"target", "--target"}});
    o.camera = cam;
    if (!background.empty()) o.background = parse_display_color(background, "--background");
    if (!front.empty()) o.front.diffuse = parse_display_color(front, "--front");
    if (!back.empty()) o.back.diffuse = parse_display_color(back, "--back");
    validate_flags([&] { validate_settings(o); }, {{"size", "--size"},
                                                   {"samples", "--aa"},
                                                   {"background", "--background"},
                                                   {"front/diffuse", "--front"},
                                                   {"back/diffuse", "--back"}});
    return o;
  }
};

void require_extension(const std::string& path, const std::string& ext, const std::string& flag) {
  if (file_extension(path) != ext)
    throw InvalidArgument(flag, path, "the file name must end in ." + ext);
}

std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

bool on_path(const std::string& program) {
  return std::system(("command -v " + program + " >/dev/null 2>&1").c_str()) == 0;
}

// ---------------------------------------------------------------------------------- render
void run_render(const SurfaceArgs& args, const LookArgs& look, const std::string& output,
                const std::string& stats_path, bool show_singular) {
  const auto& formats = image_file_extensions();
  if (std::find(formats.begin(), formats.end(), file_extension(output)) == formats.end())
    throw InvalidArgument("--output", output, "the file name must end in .png or .ppm");
  OutputTransaction outputs;
  outputs.declare(output, "--output");
  if (!stats_path.empty()) outputs.declare(stats_path, "--stats");
  const Scene scene = args.resolve();
  const Surface& surface = scene.surface;
  RenderOptions o = look.options(scene, args.spec);
  // Searched for --stats as well: the search costs milliseconds, the render far more.
  std::optional<SingularSet> singular;
  if (show_singular || !stats_path.empty()) singular = find_singular_set_if_bounded(surface);
  if (show_singular && singular) o.singular_overlay = SingularOverlay{.set = *singular};
  const FieldSurvey survey = survey_and_warn(surface);
  Progress progress("render", global_flags().quiet);
  o.progress = [&](double f) { progress.update(f); };
  RenderStats stats;
  const Image image = render_surface(surface, o, &stats);
  progress.finish();
  write_image(image, output);
  const char* method = stats.exact ? "polynomial roots" : "interval arithmetic";
  if (stats.abandoned_rays > 0)
    warn(fmt::format(
        "{}: {} of {} rays gave up after {} interval evaluations each (F undefined "
        "or unbounded along them) and are drawn as misses",
        surface.label(), stats.abandoned_rays, stats.rays, RaycastOptions{}.interval_budget));
  if (!stats_path.empty()) {
    nlohmann::json j = stats.to_json();
    j.update({{"surface", surface.label()},
              {"width", o.width},
              {"height", o.height},
              {"samples", o.samples},
              {"field", survey_json(survey)},
              {"singular_set", singular_stats(singular)}});
    write_json(j, stats_path);
  }
  outputs.commit();
  say(fmt::format("wrote {} ({}x{}, {} rays, {:.2f} s, {})", output, o.width, o.height, stats.rays,
                  stats.seconds, method));
  if (!stats_path.empty()) say("wrote " + stats_path);
}

// --------------------------------------------------------------------------------- animate
/// Frame f of an animation (0-based: the global number, whatever part a run renders).
std::string frame_file_name(int f) { return fmt::format("frame_{:04d}.png", f); }
/// The same names as an ffmpeg (printf) pattern.
std::string frame_file_name_pattern() { return "frame_%04d.png"; }

struct AnimateArgs {
  int frames = 60;
  std::string frame_range;  // A-B: only these frames of the animation
  CLI::Option* frame_range_opt = nullptr;
  double fps = 30;
  double orbit_deg = 0;
  std::string dir;
  std::string video;
  bool no_video = false;
  bool show_singular = false;
};

/// What an animation run or an animated export draws: the scene, the render options (flags
/// applied; the camera is the base the tracks move) and the tracks.
struct Animation {
  Surface surface;
  RenderOptions options;
  Keyframes keys;
};

/// The scene file's keyframes, or else --param ranges (name=from:to) and --orbit as linear
/// tracks from time 0 to 1. --param also takes fixed values (name=value). Throws
/// InvalidArgument for a flag that the keyframes make meaningless, or nothing to animate.
Animation resolve_animation(const SurfaceArgs& args, const LookArgs& look, double orbit_deg,
                            int frames) {
  // Within the camera's angle limit, so azimuth + orbit stays a valid camera.
  check_flag_range("--orbit", orbit_deg, -kMaxCameraAngleDeg / 2, kMaxCameraAngleDeg / 2);
  SurfaceOverrides overrides;
  overrides.clip_specs = args.clips;
  std::vector<ParamRange> ranges;
  for (const std::string& p : args.params) {
    const size_t eq = p.find('=');
    if (eq != std::string::npos && p.find(':', eq) != std::string::npos) {
      ranges.push_back(parse_range(p, "--param"));
      add_parameter_override(overrides, ranges.back().name, ranges.back().from, "--param", p);
    } else {
      const auto [name, value] = parse_assignment(p, "--param");
      add_parameter_override(overrides, name, value, "--param", p);
    }
  }
  const Scene scene = resolve_scene(args.spec, overrides);
  Animation an{.surface = scene.surface, .options = look.options(scene, args.spec), .keys = {}};
  an.surface.camera = *an.options.camera;
  an.keys = read_keyframes(scene.settings, an.surface, frames, args.spec);
  if (!an.keys.empty()) {
    const std::string why = "the scene's keyframes animate it; change the keyframes instead";
    if (!ranges.empty()) throw InvalidArgument("--param", ranges.front().name + "=...", why);
    if (orbit_deg != 0) throw InvalidArgument("--orbit", std::to_string(orbit_deg), why);
    for (const auto& [name, value] : overrides.params)
      if (an.keys.param(name)) throw InvalidArgument("--param", name, why);
    if (!look.camera.empty() && !an.keys.camera.empty())
      throw InvalidArgument("--camera", look.camera, why);
    return an;
  }
  if (ranges.empty() && orbit_deg == 0)
    throw InvalidArgument("--param", "(none)",
                          "give at least one range name=from:to (or --orbit, or keyframes in a "
                          "scene file) to animate");
  for (const ParamRange& r : ranges) {
    if (an.surface.field.parameter_index(r.name) < 0)
      throw InvalidArgument("--param", r.name, "the surface has no parameter of that name");
    an.keys.params.push_back(
        {.name = r.name, .times = {0, 1}, .values = {r.from, r.to}, .eases = {Ease::kLinear}});
  }
  if (orbit_deg != 0) {
    const double az = an.surface.camera.azimuth_deg;
    an.keys.camera.push_back({.name = "azimuth_deg",
                              .times = {0, 1},
                              .values = {az, az + orbit_deg},
                              .eases = {Ease::kLinear}});
  }
  return an;
}

/// The number of a frame file this command writes ("frame_0042.png": 42), else -1: files of
/// another pattern are never the command's to remove.
int frame_number_of(const std::string& name) {
  const std::string prefix = "frame_", suffix = ".png";
  if (name.size() < prefix.size() + 4 + suffix.size() || !name.starts_with(prefix) ||
      !name.ends_with(suffix))
    return -1;
  const std::string digits =
      name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
  if (digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) return -1;
  const int f = std::stoi(digits);
  return frame_file_name(f) == name ? f : -1;
}

/// Runs ffmpeg on the staged frames (`first_frame_temp`: frame 0's temp file, whose name
/// numbers them as the frames' own names do) into `video_temp`. Throws Error with its log.
void encode_video(const std::string& first_frame_temp, const std::string& video_temp, double fps,
                  const std::string& video) {
  // The temp files keep the frames' names without their extension: frame_0000 in
  // .frame_0000.tmp-TOKEN.png becomes frame_%04d.
  fs::path pattern(first_frame_temp);
  std::string name = pattern.filename().string();
  const std::string number = fs::path(frame_file_name(0)).stem().string();
  const size_t at = name.find(number);
  ZS_ASSERT(at != std::string::npos);
  name.replace(at, number.size(), fs::path(frame_file_name_pattern()).stem().string());
  pattern.replace_filename(name);
  const std::string cmd = fmt::format(
      "ffmpeg -nostdin -y -loglevel error -framerate {} -i {} -c:v libx264 -pix_fmt yuv420p "
      "-vf 'pad=ceil(iw/2)*2:ceil(ih/2)*2' {} 2>&1",
      fps, shell_quote(pattern.string()), shell_quote(video_temp));
  std::string log;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (!pipe) throw Error("cannot run ffmpeg");
  char buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, pipe)) > 0) log.append(buf, n);
  if (::pclose(pipe) != 0)
    throw Error("ffmpeg failed to encode " + video + "; no frame was written (--no-video " +
                "writes the frames alone):\n" + log);
}

void run_animate(const SurfaceArgs& args, const LookArgs& look, const AnimateArgs& a) {
  if (a.frame_range_opt->count() > 0 && a.frame_range.empty())
    throw InvalidArgument("--frame-range", "''", "expected FIRST-LAST, e.g. 0-9");
  const FrameRange range = parse_frame_range(a.frame_range, a.frames, "--frame-range");
  // Each frame is a file of the run's one transaction, and the video one more.
  if (range.count() > kMaxPendingOutputs - 1)
    throw InvalidArgument(a.frame_range.empty() ? "--frames" : "--frame-range",
                          a.frame_range.empty() ? std::to_string(a.frames) : a.frame_range,
                          fmt::format("at most {} frames in one run; render the animation in "
                                      "parts with --frame-range FIRST-LAST",
                                      kMaxPendingOutputs - 1));
  check_flag_range("--fps", a.fps, 1, 240);  // CLI::Range lets NaN through
  // A part of the animation makes no video; the frames are joined once all parts are done.
  const bool whole = range.count() == a.frames;
  if (!whole && !a.video.empty())
    throw InvalidArgument("--video", a.video,
                          "a --frame-range that is not the whole animation makes no video; "
                          "join the frames with ffmpeg when every part is rendered");
  const fs::path dir(a.dir);
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec))
    throw IoError(a.dir, "exists and is not a directory");
  // Before any work: frames can be written into DIR, or DIR can be created.
  check_writable(fs::is_directory(dir, ec) ? (dir / frame_file_name(range.first)).string() : a.dir);
  const bool want_video = !a.no_video && whole;
  const bool have_ffmpeg = want_video && on_path("ffmpeg");
  std::string video = a.video.empty() ? (dir / "animation.mp4").string() : a.video;
  if (want_video && !a.video.empty()) require_extension(video, "mp4", "--video");

  const Animation an = resolve_animation(args, look, a.orbit_deg, a.frames);
  RenderOptions o = an.options;
  // Every frame and the video are one transaction: an interrupted or failing run leaves DIR
  // as it was (docs/rendering.md, "Frames").
  OutputTransaction outputs;
  outputs.create_directories(a.dir);
  for (int f = range.first; f <= range.last; ++f)
    outputs.declare((dir / frame_file_name(f)).string(), "--output");
  if (have_ffmpeg) outputs.declare(video, "--video");
  // Frames an earlier, longer animation left beyond this one's last: ffmpeg's pattern would
  // join them into this one's video.
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const bool file = entry.is_regular_file(ec) || entry.is_symlink(ec);
    if (file && frame_number_of(entry.path().filename().string()) >= a.frames)
      outputs.remove_on_commit(entry.path().string());
  }
  // The video of an earlier run shows frames this one replaces: without a new one it goes too.
  const fs::path old_video = dir / "animation.mp4";
  const bool stale_video =
      !have_ffmpeg && (fs::is_regular_file(old_video, ec) || fs::is_symlink(old_video, ec));
  if (stale_video) outputs.remove_on_commit(old_video.string());

  Progress progress("animate", global_flags().quiet);
  for (int f = range.first; f <= range.last; ++f) {
    // The frame's time in the whole animation, whichever part of it this run renders.
    const Surface surface = an.keys.at(an.surface, frame_time(f, a.frames));
    o.camera = surface.camera;
    o.progress = [&](double x) { progress.update((f - range.first + x) / range.count()); };
    // The set of this frame's parameters: it moves with them.
    if (a.show_singular) o.singular_overlay = SingularOverlay{.set = find_singular_set(surface)};
    const Image image = render_surface(surface, o);
    write_png(image, (dir / frame_file_name(f)).string());
  }
  progress.finish();
  if (have_ffmpeg)
    encode_video(outputs.temp_path((dir / frame_file_name(0)).string()),
                 outputs.external_temp_path(video), a.fps, video);
  outputs.commit();
  if (whole)
    say(fmt::format("wrote {} frames to {}", a.frames, a.dir));
  else
    say(fmt::format("wrote frames {} to {} of {} to {}", range.first, range.last, a.frames, a.dir));
  if (have_ffmpeg)
    say("wrote " + video);
  else if (want_video)
    say("ffmpeg not found on PATH: no video (frames are in " + a.dir + ")");
  if (stale_video)
    say("removed " + old_video.string() + ", an earlier run's video of other frames");
}

// ---------------------------------------------------------------------------------- export
struct ExportArgs {
  std::string format;
  std::string output;
  bool animate = false;
  int frames = 60;
  std::string frame_range;
  double orbit_deg = 0;
  CLI::Option* frames_opt = nullptr;
  CLI::Option* frame_range_opt = nullptr;
  CLI::Option* orbit_opt = nullptr;
};

/// --animate: a clock-driven .pov and the .ini beside it that renders its frames.
void run_export_animation(const SurfaceArgs& args, const LookArgs& look, const ExportArgs& e) {
  if (e.frame_range_opt->count() > 0 && e.frame_range.empty())
    throw InvalidArgument("--frame-range", "''", "expected FIRST-LAST, e.g. 0-9");
  const FrameRange range = parse_frame_range(e.frame_range, e.frames, "--frame-range");
  fs::path ini(e.output);
  ini.replace_extension(".ini");
  OutputTransaction outputs;  // the scene and its .ini: both or neither
  outputs.declare(e.output, "--output");
  outputs.declare(ini.string(), "--output (its .ini)");
  const Animation an = resolve_animation(args, look, e.orbit_deg, e.frames);
  write_pov_animation(an.surface, an.options, an.keys,
                      PovFrames{.frames = e.frames, .first = range.first, .last = range.last},
                      e.output);
  outputs.commit();
  const fs::path dir = fs::path(e.output).parent_path();
  say(fmt::format("wrote {} and {}; render frames {} to {} of {} with: {}povray {}", e.output,
                  ini.string(), range.first, range.last, e.frames,
                  dir.empty() ? "" : "cd " + shell_quote(dir.string()) + " && ",
                  ini.filename().string()));
}

void run_export(const SurfaceArgs& args, const LookArgs& look, const ExportArgs& e) {
  std::string format = e.format;
  const std::string& output = e.output;
  if (format.empty()) format = file_extension(output) == "jsurf" ? "jsurf" : "pov";
  if (format != "pov" && format != "jsurf")
    throw InvalidArgument("--format", format, "expected pov or jsurf");
  require_extension(output, format, "--output");
  if (e.animate) {
    if (format != "pov")
      throw InvalidArgument("--format", format, "--animate writes POV-Ray scenes only");
    run_export_animation(args, look, e);
    return;
  }
  for (const CLI::Option* opt : {e.frames_opt, e.frame_range_opt, e.orbit_opt})
    if (opt->count() > 0)
      throw InvalidArgument(opt->get_name(), opt->as<std::string>(), "needs --animate");
  check_writable(output);
  const Scene scene = args.resolve();
  RenderOptions o = look.options(scene, args.spec);
  if (format == "jsurf") {
    // The picture as zeroset draws it: the camera and look the flags chose, and the default
    // light rig spelled out, since SURFER has no rig of its own.
    Scene out = scene;
    out.surface.camera = *o.camera;
    if (o.lights.empty()) o.lights = default_lights();
    out.settings = nlohmann::json::object();
    out.settings["render"] = render_settings_to_json(o);
    write_jsurf(out, output);
    say(fmt::format("wrote {}; open it in SURFER, or with zeroset view {}", output, output));
    return;
  }
  write_pov_scene(scene.surface, o, output);
  say(fmt::format("wrote {}; render it with: povray +W{} +H{} +A0.1 +I{} +O{}.png", output, o.width,
                  o.height, output, fs::path(output).stem().string()));
}

}  // namespace

void register_render_commands(CLI::App& app) {
  {
    auto* cmd = app.add_subcommand(
        "render",
        "Ray trace a surface into a picture (PNG, or PPM for pipelines).\n\n"
        "Polynomial surfaces are cast exactly: the equation is restricted to each ray and its\n"
        "first root isolated robustly, so nodes show as sharp double cones and\n"
        "self-intersections as clean curves. Other expressions use interval arithmetic.\n"
        "The side ∇F points to is drawn in the front colour, the other side darker.\n\n"
        "Examples:\n"
        "  zeroset render kummer --param mu=1.5 -o kummer.png\n"
        "  zeroset render barth6 --size 1200x900 --aa 3 -o barth.png\n"
        "  zeroset render \"x^2 + y^2 - z^2\" --clip sphere:1.5 --camera 30,20 -o cone.png\n"
        "  zeroset render roman --background '#202020' --stats roman.json -o roman.png\n"
        "  zeroset render cayley --aa 1 -o cayley.ppm    (uncompressed, for pipelines)\n"
        "  zeroset render whitney --show-singular -o whitney.png   (the umbrella's handle too)");
    auto args = std::make_shared<SurfaceArgs>();
    auto look = std::make_shared<LookArgs>();
    auto output = std::make_shared<std::string>();
    auto stats = std::make_shared<std::string>();
    args->add_to(cmd);
    look->add_to(cmd);
    cmd->add_option("-o,--output", *output,
                    "Output picture: .png, or .ppm (binary netpbm, uncompressed: the fastest "
                    "to write)")
        ->required()
        ->type_name("FILE");
    cmd->add_option("--stats", *stats,
                    "Write figures (rays, hits, seconds, the singular set found) as JSON to FILE")
        ->type_name("FILE");
    auto show_singular = std::make_shared<bool>(false);
    add_show_singular_flag(cmd, *show_singular, "the picture");
    cmd->callback([=] { run_render(*args, *look, *output, *stats, *show_singular); });
  }
  {
    auto* cmd = app.add_subcommand(
        "animate",
        "Render a parameter animation: numbered PNGs in a directory, and an MP4 when ffmpeg\n"
        "is on PATH.\n\n"
        "--param takes fixed values (name=value) and animated ranges (name=from:to); every\n"
        "range goes linearly from its first to its last value over the frames.\n\n"
        "Examples:\n"
        "  zeroset animate kummer --param mu=0.34:3.0 --frames 60 -o kummer-frames\n"
        "  zeroset animate torus --param r=0.2:0.9 --orbit 90 --size 480x480 -o torus\n"
        "  zeroset animate planes --param a=-0.5:0.5 --no-video -o planes\n"
        "  zeroset animate kummer --param mu=0.34:3.0 --frames 600 --frame-range 100-199 -o k\n"
        "                          (frames 100 to 199 of 600: frame_0100.png ... frame_0199.png)");
    auto args = std::make_shared<SurfaceArgs>();
    auto look = std::make_shared<LookArgs>();
    auto a = std::make_shared<AnimateArgs>();
    args->add_to(cmd);
    cmd->get_option("--param")
        ->description("Animated range name=from:to, or fixed value name=value (repeatable)")
        ->type_name("NAME=A:B");
    look->add_to(cmd);
    cmd->add_option("-o,--output", a->dir, "Output directory for frame_0000.png, ...")
        ->required()
        ->type_name("DIR");
    cmd->add_option("--frames", a->frames, "Number of frames of the whole animation")
        ->capture_default_str();
    a->frame_range_opt =
        cmd->add_option(
               "--frame-range", a->frame_range,
               "Render only frames FIRST to LAST (both included, counted from 0 as the file "
               "names) of the --frames animation, e.g. to share it out over the nodes of a "
               "cluster; no video unless it is the whole animation")
            ->type_name("FIRST-LAST");
    cmd->add_option("--fps", a->fps, "Frames per second of the video")
        ->check(CLI::Range(1.0, 240.0))
        ->capture_default_str();
    cmd->add_option("--orbit", a->orbit_deg,
                    "Turn the camera's azimuth by this many degrees over the animation");
    cmd->add_option("--video", a->video, "Video file (default: DIR/animation.mp4)")
        ->type_name("FILE.mp4");
    cmd->add_flag("--no-video", a->no_video, "Only write the frames, even if ffmpeg is there");
    add_show_singular_flag(cmd, a->show_singular, "every frame (found anew for each frame)");
    cmd->callback([=] { run_animate(*args, *look, *a); });
  }
  {
    auto* cmd = app.add_subcommand(
        "export",
        "Export the view as a POV-Ray 3.7 scene (--format pov, the default): the surface as a\n"
        "`polynomial` with `sturm`, `clipped_by` the clip volume, and the same camera, lights\n"
        "and colours (the back side as interior_texture). Needs a polynomial surface.\n\n"
        "Or as a SURFER file (--format jsurf, or an output name ending in .jsurf): the\n"
        "equation with its parameters renamed to a..d, scale_factor from the clip sphere,\n"
        "rotation_matrix and camera_transform from the camera, colours and lights. Needs a\n"
        "polynomial with at most 4 parameters, clipped to one sphere about the origin.\n\n"
        "Examples:\n"
        "  zeroset export kummer --param mu=2.44 -o kummer.pov\n"
        "  povray +W800 +H800 +A0.1 +Ikummer.pov +Okummer.png\n"
        "  zeroset export kummer --camera 40,25 --front '#3060c0' -o kummer.jsurf\n"
        "  zeroset export kummer --animate --param mu=0.5:2.5 --frames 60 -o k.pov\n"
        "  povray k.ini    (frames k_00.png ... k_59.png)");
    auto args = std::make_shared<SurfaceArgs>();
    auto look = std::make_shared<LookArgs>();
    auto e = std::make_shared<ExportArgs>();
    args->add_to(cmd);
    cmd->get_option("--param")
        ->description(
            "Fixed value name=value, or with --animate an animated range name=from:to "
            "(repeatable)")
        ->type_name("NAME=V|A:B");
    look->add_to(cmd, false);
    cmd->add_option("-o,--output", e->output, "Output .pov or .jsurf file")
        ->required()
        ->type_name("FILE");
    cmd->add_option("--format", e->format,
                    "pov (POV-Ray) or jsurf (SURFER); default: from the output's extension, "
                    "else pov")
        ->type_name("FORMAT");
    cmd->add_flag("--animate", e->animate,
                  "Write an animation: a .pov driven by POV-Ray's clock and FILE.ini beside it "
                  "(the scene file's keyframes, or --param ranges and --orbit, as animate)");
    e->frames_opt = cmd->add_option("--frames", e->frames,
                                    "With --animate: number of frames of the whole animation")
                        ->capture_default_str();
    e->frame_range_opt =
        cmd->add_option("--frame-range", e->frame_range,
                        "With --animate: the .ini renders only frames FIRST to LAST (from 0)")
            ->type_name("FIRST-LAST");
    e->orbit_opt = cmd->add_option(
        "--orbit", e->orbit_deg,
        "With --animate: turn the camera's azimuth by this many degrees over the animation");
    cmd->callback([=] { run_export(*args, *look, *e); });
  }
}

}  // namespace zeroset::cli
