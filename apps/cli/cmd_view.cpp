// zeroset view: the interactive viewer (built with ZEROSET_BUILD_VIEWER=ON).
#include <memory>
#include <string>

#include "common.h"
#include "zeroset/error.h"

#if defined(ZEROSET_HAVE_VIEWER)
#include "viewer.h"
#endif

namespace zeroset::cli {
namespace {

constexpr const char* kDescription =
    "Open the interactive viewer: floaters, mesh or ray-traced preview, with parameter\n"
    "sliders and animation (GLFW + OpenGL 3.3 + Dear ImGui). SURFACE defaults to kummer.\n"
    "  e.g. zeroset view kummer --mode floaters\n"
    "       zeroset view cone --screenshot cone.png --frames 30 --no-ui\n"
    "       zeroset view kummer --script demo.txt\n"
    "Controls: left drag orbits, right drag pans, wheel zooms, R resets the view, space plays\n"
    "the animation, 1/2/3 switch modes, H hides the panel. See docs/viewer.md.";

#if defined(ZEROSET_HAVE_VIEWER)

struct ViewArgs {
  SurfaceArgs surface;
  std::string mode;
  std::string size = "1280x800";
  std::string screenshot;
  int frames = 0;
  bool wait = false;
  std::string script;
  bool no_ui = false;
  std::string stats_out;
};

int run_view(const ViewArgs& a) {
  viewer::ViewerOptions o;
  SurfaceArgs surface = a.surface;
  if (surface.spec.empty()) surface.spec = "kummer";
  o.scene = surface.resolve();
  o.scene_origin = surface.spec;
  if (!a.mode.empty()) o.mode = viewer::parse_mode(a.mode, "--mode");
  std::tie(o.width, o.height) = parse_size(a.size, "--size");
  o.screenshot = a.screenshot;
  o.frames = a.frames;
  o.wait = a.wait;
  o.script = a.script;
  o.show_ui = !a.no_ui;
  o.stats_out = a.stats_out;
  o.threads = global_flags().threads;
  o.quiet = global_flags().quiet;
  return viewer::run_viewer(o);
}

#endif

}  // namespace

void register_view_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("view", kDescription);
#if defined(ZEROSET_HAVE_VIEWER)
  auto a = std::make_shared<ViewArgs>();
  a->surface.add_to(cmd, /*optional=*/true);
  cmd->add_option("--mode", a->mode,
                  "floaters, mesh or raytrace (default: the scene's, else raytrace)")
      ->type_name("MODE");
  cmd->add_option("--size", a->size, "Window size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--screenshot", a->screenshot,
                  "Run --frames frames (after --script and --wait), save the last as PNG and exit")
      ->type_name("FILE.png");
  cmd->add_option("--frames", a->frames,
                  "Frames to run before exiting (default 60 with --screenshot)")
      ->check(CLI::Range(0, 1000000));
  cmd->add_flag("--wait", a->wait,
                "Before those frames, wait (up to 60 s) until the mode's work is done: full "
                "resolution, mesh improved, floaters at rest");
  cmd->add_option("--script", a->script,
                  "Run the viewer commands in FILE (one per line, see docs/viewer.md), then exit")
      ->type_name("FILE");
  cmd->add_flag("--no-ui", a->no_ui, "Hide the panel (H shows it again)");
  cmd->add_option("--stats-out", a->stats_out,
                  "Write the final figures (frames/s, floater steps/s, counts) as JSON")
      ->type_name("FILE.json");
  cmd->callback([a] {
    if (run_view(*a) != 0) throw Error("the viewer's commands did not all succeed (see above)");
  });
#else
  cmd->allow_extras();
  cmd->callback([] {
    throw Error(
        "this zeroset was built without the viewer: configure with -DZEROSET_BUILD_VIEWER=ON "
        "(needs GLFW, libepoxy and Dear ImGui; scripts/install-deps.sh installs them)");
  });
#endif
}

}  // namespace zeroset::cli
