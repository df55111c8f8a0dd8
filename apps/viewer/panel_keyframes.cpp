// The panel's Keyframes section: the list of keyframes (time, ease), recording the current
// parameters and camera into a new or an existing keyframe, and scrubbing the animation time.
// Every widget calls the ViewerState action the `keyframe` command calls.
#include <imgui.h>

#include <algorithm>
#include <array>
#include <climits>
#include <optional>
#include <string>

#include "panel.h"

namespace zeroset::viewer {
namespace {

constexpr std::array<Ease, 4> kEases = {Ease::kLinear, Ease::kIn, Ease::kOut, Ease::kInOut};

void tooltip(const char* text) {
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", text);
}

// A combo of the eases; returns true when the user chose one.
bool ease_combo(const char* id, Ease& ease) {
  bool chosen = false;
  ImGui::SetNextItemWidth(80);
  if (ImGui::BeginCombo(id, ease_name(ease))) {
    for (Ease e : kEases)
      if (ImGui::Selectable(ease_name(e), e == ease)) {
        ease = e;
        chosen = true;
      }
    ImGui::EndCombo();
  }
  tooltip(
      "How the values move towards the next keyframe: linear, in (start slowly), out (end "
      "slowly) or in-out (both)");
  return chosen;
}

}  // namespace

void keyframes_section(ViewerState& state, PanelState& panel) {
  // Open at first for a scene that came with keyframes.
  if (!ImGui::CollapsingHeader("Keyframes",
                               state.has_keyframes() ? ImGuiTreeNodeFlags_DefaultOpen : 0))
    return;
  std::size_t count = state.keyframes().size();
  if (count == 0) ImGui::TextDisabled("no keyframes: Play animates one parameter");
  // A row's Delete takes effect after the table: the rows below it would otherwise ask for
  // keyframes that are no longer there.
  std::optional<std::size_t> deleted;
  // Only the rows in view are drawn, and the frame count that places keyframes given by frame
  // is found once: drawing every row, each finding it again, took 3.3 s a frame at 20,000
  // keyframes.
  const int frames = state.keyframe_frames();
  if (ImGui::BeginTable("keyframes", 4, ImGuiTableFlags_SizingFixedFit)) {
    ImGuiListClipper clipper;
    clipper.Begin(static_cast<int>(std::min<std::size_t>(count, INT_MAX)));
    while (clipper.Step()) {
      for (std::size_t i = static_cast<std::size_t>(clipper.DisplayStart);
           i < static_cast<std::size_t>(clipper.DisplayEnd); ++i) {
        ImGui::PushID(static_cast<int>(i));
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::Text("%zu", i);
        ImGui::TableNextColumn();
        ImGui::Text("t = %.4g", state.keyframe_time(i, frames));
        ImGui::TableNextColumn();
        Ease e = state.keyframe_ease(i);
        if (ease_combo("##ease", e)) state.set_keyframe_ease(i, e);
        ImGui::TableNextColumn();
        if (ImGui::SmallButton("Show")) state.scrub_keyframes(state.keyframe_time(i, frames));
        tooltip("Show this keyframe's parameters and camera");
        ImGui::SameLine();
        if (ImGui::SmallButton("Update")) state.update_keyframe(i);
        tooltip("Record the current parameters and camera into this keyframe");
        ImGui::SameLine();
        if (ImGui::SmallButton("Delete")) deleted = i;
        tooltip("Remove this keyframe");
        ImGui::PopID();
      }
    }
    ImGui::EndTable();
  }
  if (deleted) {
    state.delete_keyframe(*deleted);
    count = state.keyframes().size();
  }
  ImGui::SetNextItemWidth(120);
  ImGui::InputDouble("##new-time", &panel.keyframe_time, 0.05, 0.25, "%.4g");
  tooltip("Animation time of the new keyframe: 0 is the first frame, 1 the last");
  ImGui::SameLine();
  ease_combo("##new-ease", panel.keyframe_ease);
  ImGui::SameLine();
  if (ImGui::Button("Add")) state.add_keyframe(panel.keyframe_time, panel.keyframe_ease);
  tooltip("Record the current parameters and camera as a keyframe at this time");
  if (count > 0) {
    double t = state.keyframe_playhead();
    const double lo = 0, hi = 1;
    if (ImGui::SliderScalar("Time", ImGuiDataType_Double, &t, &lo, &hi, "%.3f"))
      state.scrub_keyframes(t);
    tooltip(
        "Scrub: show the animation at this time (Play runs through it at Speed "
        "animations per second)");
    if (ImGui::Button("Clear all")) state.clear_keyframes();
    tooltip("Remove every keyframe; Play then animates one parameter again");
  }
}

}  // namespace zeroset::viewer
