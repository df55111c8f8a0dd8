#pragma once
// `zeroset view`: the interactive window (GLFW, OpenGL 3.3 core, Dear ImGui). The CLI resolves
// the surface and turns its flags into ViewerOptions; everything else happens here.
#include <optional>
#include <string>
#include <string_view>

#include "zeroset/surface/scene.h"

namespace zeroset::viewer {

/// What the 3D view shows.
enum class Mode {
  kFloaters,  ///< a live floater simulation, drawn as shaded disks or points
  kMesh,      ///< marching cubes on a worker thread, then the improver step by step
  kRaytrace,  ///< progressive CPU ray casting (1/8 resolution first, then finer)
};

/// "floaters", "mesh" or "raytrace".
std::string_view to_string(Mode mode);
/// Parses a mode name (also "raytraced" and "ray"); throws InvalidArgument naming `flag`.
Mode parse_mode(std::string_view text, std::string_view flag = "mode");

struct ViewerOptions {
  Scene scene;                         ///< the surface to open with, and its saved settings
  std::string scene_origin = "scene";  ///< names the scene in messages (its file name)
  std::optional<Mode> mode;            ///< nullopt: the scene's saved mode, else ray tracing
  int width = 1280;                    ///< window size in screen coordinates
  int height = 800;
  bool show_ui = true;  ///< false: the picture only (the panel can be shown again with H)
  /// Save the last of `frames` frames as PNG and exit (with `script`: after the script).
  std::string screenshot;
  /// Frames to run before the screenshot (0: 60 with a screenshot, else until the window is
  /// closed).
  int frames = 0;
  /// Before the screenshot's frames, wait (up to 60 s) until the mode's work is done: the ray
  /// caster at full resolution, the mesh polygonized and improved.
  bool wait = false;
  /// A file of viewer commands (see docs/viewer.md), run one after the other; the viewer
  /// exits after the last.
  std::string script;
  /// Write the final statistics (frame rate, floater steps per second, ...) as JSON here.
  std::string stats_out;
  int threads = 0;     ///< worker threads for the simulation and ray caster; 0: all cores
  bool quiet = false;  ///< no script log on stdout
};

/// Opens the window and runs until it is closed, or until the screenshot / script is done.
/// Returns the process exit code: 0 on success, 1 when the window cannot be opened or a
/// scripted command failed without `expect-error`. Throws BadInput (before opening a window)
/// for bad options: unreadable or malformed script, unwritable output paths.
int run_viewer(const ViewerOptions& options);

}  // namespace zeroset::viewer
