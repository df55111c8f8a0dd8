#pragma once
// The Dear ImGui control panel: surface (catalog, equation with its diagnostics, parameter
// sliders and animation), mode and its settings and live figures, clip, look, files, and a
// command line. Every widget change becomes an action of ViewerState.
#include <string>

#include "viewer_state.h"

struct ImFont;

namespace zeroset::viewer {

/// Widget state that is not the viewer's state (text being edited, file names).
struct PanelState {
  std::string equation;        ///< the equation field while it is being edited
  std::string shown_equation;  ///< the state's equation text the field was last filled from
  std::string command;
  std::string scene_path = "zeroset-scene.json";
  std::string screenshot_path = "zeroset-screenshot.png";
  std::string mesh_path = "zeroset-mesh.ply";
  std::string floaters_path = "zeroset-floaters.ply";
  std::string pov_path = "zeroset-scene.pov";
  double keyframe_time = 0;           ///< time of the next keyframe the Add button records
  Ease keyframe_ease = Ease::kInOut;  ///< and its ease
  bool wants_screenshot = false;      ///< set by the Save button (or F12); the window saves it
  ImFont* mono_font = nullptr;        ///< for the equation and its diagnostics (nullptr: default)
};

/// Width of the panel in screen coordinates.
inline constexpr float kPanelWidth = 360;

/// The Keyframes section (panel_keyframes.cpp).
void keyframes_section(ViewerState& state, PanelState& panel);

/// Draws the panel at the left edge of the window, `height` tall, inside an ImGui frame.
void draw_panel(ViewerState& state, PanelState& panel, float height);

}  // namespace zeroset::viewer
