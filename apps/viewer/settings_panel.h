#pragma once
// The settings of the floaters and mesh modes in the panel: one table entry per key of the
// scene file's "floaters" and "mesh" objects, each drawn as a widget with a tooltip saying
// what docs/floaters.md, docs/meshing.md and docs/algorithms.md say about it. A change goes
// through ViewerState::set_settings, the path of the `set` command and of scene files, so the
// panel checks values with the same words. A new setting is one entry in setting_widgets().
#include <string_view>
#include <vector>

namespace zeroset::viewer {

class ViewerState;

enum class WidgetKind {
  kSwitch,   ///< true or false: a checkbox
  kWhole,    ///< a whole number: a slider over [min, max]
  kNumber,   ///< a number: a slider over [min, max] (× the scene radius if scene_relative)
  kChoice,   ///< one of `choices`: a combo box
  kImprove,  ///< the mesh's "improve": a checkbox and a step limit (0 on the slider: auto)
};

struct SettingWidget {
  std::string_view object;  ///< "floaters" or "mesh"
  std::string_view key;     ///< its key in the scene file's object (`set OBJECT.KEY VALUE`)
  std::string_view label;
  WidgetKind kind = WidgetKind::kSwitch;
  /// The slider's span. Values beyond it stay settable by the `set` command and scene files
  /// as far as the scene file's rule allows.
  double min = 0;
  double max = 0;
  bool logarithmic = false;
  bool scene_relative = false;  ///< kNumber: min and max are in scene radii
  std::string_view zero_label;  ///< what a slider shows at 0 ("auto", "off"), if special
  std::string_view choices;     ///< kChoice: the values, separated by '|'
  std::string_view tooltip;
};

/// Every widget, in the order the panel draws them within its object.
const std::vector<SettingWidget>& setting_widgets();

/// Draws the widgets of `object` ("floaters" or "mesh") for the current settings, applying a
/// change at once (the floaters take it live, the mesh starts again).
void draw_setting_widgets(ViewerState& state, std::string_view object);

}  // namespace zeroset::viewer
