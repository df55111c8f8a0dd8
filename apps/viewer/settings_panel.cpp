#include "settings_panel.h"

#include <imgui.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "viewer_state.h"
#include "zeroset/mesh/settings.h"

namespace zeroset::viewer {
namespace {

using json = nlohmann::json;

// What the panel's Dear ImGui (1.86, before SetItemTooltip) shows over the last widget.
void tooltip(std::string_view text, ImGuiHoveredFlags flags = 0) {
  if (!ImGui::IsItemHovered(flags)) return;
  ImGui::BeginTooltip();
  ImGui::PushTextWrapPos(ImGui::GetFontSize() * 28);
  ImGui::TextUnformatted(text.data(), text.data() + text.size());
  ImGui::PopTextWrapPos();
  ImGui::EndTooltip();
}

void apply(ViewerState& state, const SettingWidget& w, json value) {
  state.set_settings(w.object, json{{std::string(w.key), std::move(value)}}, w.object);
}

void draw_switch(ViewerState& state, const SettingWidget& w, const json& value) {
  bool on = value.is_boolean() && value.get<bool>();
  if (ImGui::Checkbox(std::string(w.label).c_str(), &on)) apply(state, w, on);
  tooltip(w.tooltip);
}

void draw_whole(ViewerState& state, const SettingWidget& w, const json& value) {
  long long v = value.is_number() ? value.get<long long>() : 0;
  const long long lo = static_cast<long long>(w.min), hi = static_cast<long long>(w.max);
  const char* format = v == 0 && !w.zero_label.empty() ? w.zero_label.data() : "%lld";
  if (ImGui::SliderScalar(std::string(w.label).c_str(), ImGuiDataType_S64, &v, &lo, &hi, format,
                          w.logarithmic ? ImGuiSliderFlags_Logarithmic : 0))
    apply(state, w, v);
  tooltip(w.tooltip);
}

void draw_number(ViewerState& state, const SettingWidget& w, const json& value) {
  double v = value.is_number() ? value.get<double>() : 0;
  double scale = 1;
  if (w.scene_relative) {
    const double r = state.surface().scene_radius();
    scale = std::isfinite(r) && r > 0 ? r : 1;
  }
  const double lo = w.min * scale, hi = w.max * scale;
  const std::string format =
      v == 0 && !w.zero_label.empty() ? std::string(w.zero_label) : std::string("%.4g");
  if (ImGui::SliderScalar(std::string(w.label).c_str(), ImGuiDataType_Double, &v, &lo, &hi,
                          format.c_str(), w.logarithmic ? ImGuiSliderFlags_Logarithmic : 0))
    apply(state, w, v);
  tooltip(w.tooltip);
}

void draw_choice(ViewerState& state, const SettingWidget& w, const json& value) {
  const std::string current = value.is_string() ? value.get<std::string>() : std::string();
  if (ImGui::BeginCombo(std::string(w.label).c_str(), current.c_str())) {
    std::string_view rest = w.choices;
    while (!rest.empty()) {
      const size_t bar = rest.find('|');
      const std::string choice(rest.substr(0, bar));
      rest = bar == std::string_view::npos ? std::string_view{} : rest.substr(bar + 1);
      if (ImGui::Selectable(choice.c_str(), choice == current) && choice != current)
        apply(state, w, choice);
    }
    ImGui::EndCombo();
  }
  tooltip(w.tooltip);
}

// "improve": true ("auto"), false, or a number of steps.
void draw_improve(ViewerState& state, const SettingWidget& w, const json& value) {
  bool on = !(value.is_boolean() && !value.get<bool>());
  if (ImGui::Checkbox(std::string(w.label).c_str(), &on)) apply(state, w, on);
  tooltip(w.tooltip);
  if (!on) return;
  int steps = value.is_number() ? value.get<int>() : 0;
  const int lo = static_cast<int>(w.min), hi = static_cast<int>(w.max);
  if (ImGui::SliderInt("Max steps", &steps, lo, hi, steps == 0 ? "auto" : "%d",
                       w.logarithmic ? ImGuiSliderFlags_Logarithmic : 0))
    apply(state, w, steps == 0 ? json("auto") : json(steps));
  tooltip(
      "At most this many remesher iterations or paper improver steps; auto (0): until at "
      "rest, at most 30 iterations of the remesher; for the paper's improver until every "
      "vertex moves less than 0.005 mean edge lengths in a step, at most 200 steps live "
      "(300 in zeroset mesh).");
}

}  // namespace

const std::vector<SettingWidget>& setting_widgets() {
  using K = WidgetKind;
  // One row a setting, laid out by hand: the fields of a row read as one line.
  // clang-format off
  static const std::vector<SettingWidget> table = {
      // ---- floaters (docs/floaters.md, docs/algorithms.md A and B) ----
      {.object = "floaters", .key = "max_count", .label = "Max count", .kind = K::kWhole,
       .min = 50, .max = 200000, .logarithmic = true,
       .tooltip = "Population cap: no fission beyond it. The viewer simulates up to 2,000,000 "
                  "floaters live; type more with `set floaters.max_count N`."},
      {.object = "floaters", .key = "radius", .label = "Density", .kind = K::kNumber,
       .min = 0, .max = 0.25, .scene_relative = true, .zero_label = "auto",
       .tooltip = "sigma-hat, the nominal repulsion radius: smaller means denser (spacing at rest "
                  "about 1.5 sigma-hat). 0 (auto) chooses it from the surface's area so that "
                  "about a third of Max count cover it, leaving room for the refinement near "
                  "singular points."},
      {.object = "floaters", .key = "scaled_repulsion", .label = "Scaled pair forces",
       .kind = K::kSwitch,
       .tooltip = "On: pair forces use the pair's mean radius and scale with it, so a graded "
                  "density is an equilibrium. Off: the paper's plain repulsion (A.2, eq. 5), "
                  "where the dense side always pushes towards the sparse side and fission near "
                  "nodes and death elsewhere never stop (0.24% of the floaters per step on "
                  "Kummer mu = 1.5 against 0.05%, docs/floaters.md)."},
      {.object = "floaters", .key = "radius_grading", .label = "Grading", .kind = K::kNumber,
       .min = 0, .max = 1, .zero_label = "off",
       .tooltip = "Grading g of the fission radii: sigma_max_i <= sigma_max_j + g |p_i - p_j| "
                  "between neighbours (0.1 by default), so the wanted density changes gradually "
                  "where the curvature estimator jumps across a node and fission and death do "
                  "not fight. 0: off, the paper's raw sigma_max_i."},
      {.object = "floaters", .key = "feedback", .label = "Feedback phi", .kind = K::kNumber,
       .min = 0, .max = 60,
       .tooltip = "phi, the pull towards F = 0 in the constrained velocity (A.4): "
                  "p' = P - [(F_x.P + F_q.q' + phi F)/|F_x|^2] F_x (15 by default). Small: "
                  "floaters drift off the surface and trail it while parameters move; large: a "
                  "step overshoots F = 0 (phi dt > 1 with dt = 0.03), and from phi dt = 2 on "
                  "it diverges, so phi stays below 66.7."},
      {.object = "floaters", .key = "equilibrium_speed", .label = "Equilibrium gamma",
       .kind = K::kNumber, .min = 0.1, .max = 16,
       .tooltip = "gamma: a floater is near equilibrium when |p'| < gamma sigma_i (A.7, 4 by "
                  "default); only such floaters may split or die. Small: fission and death wait "
                  "until floaters are almost still; large: they act while floaters still move."},
      {.object = "floaters", .key = "estimator_interval", .label = "Estimator steps",
       .kind = K::kWhole, .min = 1, .max = 100, .logarithmic = true,
       .tooltip = "Steps between refreshes of the curvature and singularity estimators "
                  "(alpha_i, beta_i) and node snapping (8 by default): shorter follows moving "
                  "parameters sooner, at the cost of Hessians every few steps."},
      {.object = "floaters", .key = "radius_adapt", .label = "Adaptation", .kind = K::kChoice,
       .choices = "wh|curvature|singular|mixed",
       .tooltip = "How each floater's largest radius before fission is chosen (paper 3.3, B.4): "
                  "wh one sigma_max for all (Witkin-Heckbert), curvature from alpha_i, singular "
                  "from the distance to a singular point beta_i, mixed alpha/3 + 2 beta/3 (the "
                  "paper's): denser sampling near nodes and creases."},
      {.object = "floaters", .key = "cos_weight", .label = "Cosine weighting", .kind = K::kSwitch,
       .tooltip = "Weight repulsion by |cos| of the angle between normals (B.1, paper 3.3), so "
                  "sheets crossing at a self-intersection pass through each other."},
      {.object = "floaters", .key = "snap_to_nodes", .label = "Snap to nodes", .kind = K::kSwitch,
       .tooltip = "A floater that comes near a node (an isolated singular point) moves onto it "
                  "and stays there, following it while parameters move; the same switch holds "
                  "floaters on the rest of the singular set (B.7)."},
      {.object = "floaters", .key = "clip_projection", .label = "Clip projection",
       .kind = K::kSwitch,
       .tooltip = "Floaters leaving the clip volume are projected back onto its boundary and "
                  "onto F = 0 along it (paper 3.2); off: they are removed, as in the unclipped "
                  "method."},
      {.object = "floaters", .key = "clip_newton", .label = "Newton onto clip curve",
       .kind = K::kSwitch,
       .tooltip = "After the projection onto the clip, Newton steps along the boundary onto "
                  "F = 0 and the boundary at once (A.6). Off: the paper's projection alone; "
                  "floaters on the clip boundary stay off F = 0 (0.29 sigma-hat on the cone)."},
      {.object = "floaters", .key = "average_radius_factor", .label = "Average mu",
       .kind = K::kSwitch,
       .tooltip = "mu_i, the radius factor of paper 3.3, is averaged with its previous value "
                  "(B.4). Off: the paper's mu_i, this refresh's estimate alone; alpha_i samples "
                  "random perimeter points, so sigma_max_i jumps between refreshes."},
      {.object = "floaters", .key = "local_nominal_radius", .label = "Local sigma-hat",
       .kind = K::kSwitch,
       .tooltip = "Fission and death compare with the local nominal radius "
                  "min(sigma-hat, sigma_max_i) (A.7). Off: the paper's sigma-hat, so floaters "
                  "made small near a singular point die and are made again by fission, a churn "
                  "that never settles."},
      {.object = "floaters", .key = "energy_taper", .label = "Energy taper", .kind = K::kSwitch,
       .tooltip = "The pair energy is tapered by (1 - |r|^2/9 sigma^2) to reach zero at 3 sigma "
                  "(A.1). Off: Witkin-Heckbert's plain Gaussian, cut off at 3 sigma; radii settle "
                  "smaller for the same spacing."},
      {.object = "floaters", .key = "fission_offset", .label = "Offset child", .kind = K::kSwitch,
       .tooltip = "At fission the child starts a little away from its parent (A.7). Off: "
                  "Witkin-Heckbert's plain split, the child where the parent is; the pair forces "
                  "separate the twins."},
      {.object = "floaters", .key = "seed_count", .label = "Seeds", .kind = K::kWhole, .min = 0,
       .max = 5000, .logarithmic = true, .zero_label = "auto",
       .tooltip = "Random insertions into the clip volume at the start and after a reset (A.8); "
                  "0 (auto): min(Max count, 200). Fission fills the surface from them."},
      {.object = "floaters", .key = "seed", .label = "Random seed", .kind = K::kWhole, .min = 0,
       .max = 1000,
       .tooltip = "Every random choice derives from it: same seed, same floaters."},
      // ---- mesh (docs/meshing.md, docs/algorithms.md C) ----
      {.object = "mesh", .key = "cells", .label = "Cells", .kind = K::kWhole, .min = 4,
       .max = 512, .logarithmic = true,
       .tooltip = "Marching cubes cells along the longest side of the clip box (4 to 512 live; "
                  "zeroset mesh --resolution takes up to 32768)."},
      {.object = "mesh", .key = "grid", .label = "Grid", .kind = K::kChoice,
       .choices = "auto|dense|sparse",
       .tooltip = "dense samples every grid node; sparse only bricks of 8^3 cells where a "
                  "first-order distance test says the surface may pass (it can miss pieces "
                  "smaller than a brick); auto: sparse above 300^3 nodes."},
      {.object = "mesh", .key = "refine_steps", .label = "Refine steps", .kind = K::kWhole,
       .min = 0, .max = 64, .zero_label = "linear",
       .tooltip = "Steps placing each vertex onto F = 0 along its grid edge, one evaluation of F "
                  "each (12 by default); 0: linear interpolation, as classic marching cubes."},
      {.object = "mesh", .key = "crossings", .label = "Exact crossings", .kind = K::kSwitch,
       .tooltip = "Sheets that cross along a singular curve meet exactly on it; off: as marching "
                  "cubes makes them, rounded off a cell away from the curve."},
      {.object = "mesh", .key = "curves", .label = "Curves in mesh files", .kind = K::kSwitch,
       .tooltip = "Save Mesh writes the singular curves (OBJ l lines, PLY edges); off: "
                  "triangles only."},
      {.object = "mesh", .key = "improve", .label = "Improve", .kind = K::kImprove, .min = 0,
       .max = 2000, .logarithmic = true,
       .tooltip = "Run the improver after marching cubes: the remesher, or the paper's "
                  "spring-mass system on F = 0 (section 4) that evens out the triangles and "
                  "pulls vertices into creases and singular points."},
      {.object = "mesh", .key = "improver", .label = "Improver", .kind = K::kChoice,
       .choices = "remesh|paper",
       .tooltip = "remesh (the default): isotropic remeshing (split long edges, collapse short "
                  "ones, flip towards valence 6, relax in the tangent plane) with singular "
                  "points, singular curves and the clip curve kept exactly; shown when done. "
                  "paper: the spring-mass improver of the paper, step by step, with the "
                  "settings below that are greyed out for the remesher."},
      {.object = "mesh", .key = "boundary", .label = "Boundary", .kind = K::kChoice,
       .choices = "constrain|fix",
       .tooltip = "Boundary vertices fixed where marching cubes cut them, or sliding along the "
                  "clip curve F = 0, G = 0 under the second constraint G_x.p' + phi G = 0 "
                  "(paper 4.2)."},
      {.object = "mesh", .key = "curvature", .label = "Curvature springs", .kind = K::kSwitch,
       .tooltip = "Springs with the curvature estimator kappa_d (1 - cos(n_i, n_j)) (paper "
                  "eq. 6): stiffer where the normals turn, so vertices gather in curved parts "
                  "and creases. Off: kappa_0 and the singularity term only."},
      {.object = "mesh", .key = "curvature_weight", .label = "kappa_d", .kind = K::kNumber,
       .min = 0, .max = 50,
       .tooltip = "kappa_d, the weight of the curvature estimator in the spring constants "
                  "kappa_ij = kappa_0 + kappa_d (1 - cos(n_i, n_j)) + kappa_s (1 - min(beta_i, "
                  "beta_j)); 8 by default, kappa_0 = 1."},
      {.object = "mesh", .key = "singularity", .label = "Singularity springs",
       .kind = K::kSwitch,
       .tooltip = "Springs with the floaters' singularity estimator beta (kappa_s = 4): stiffer "
                  "near points where grad F = 0, so the mesh is finer there."},
      {.object = "mesh", .key = "flips", .label = "Edge flips", .kind = K::kSwitch,
       .tooltip = "Delaunay flips between nearly coplanar triangles (dihedral < 25 degrees) "
                  "during the first 40 steps: vertex motion cannot change the valences marching "
                  "cubes leaves (without flips the Kummer mesh at 128 cells keeps about 12% of "
                  "its triangles below 30 degrees)."},
      {.object = "mesh", .key = "find_singular", .label = "Find singular points",
       .kind = K::kSwitch,
       .tooltip = "Newton's method on grad F = 0 from vertices whose Newton step is shorter than "
                  "an edge; the nearest vertex is moved onto each point found and held."},
  };
  // clang-format on
  return table;
}

void draw_setting_widgets(ViewerState& state, std::string_view object) {
  const json current = state.settings_object(object);
  // The paper improver's own settings do nothing for the remesher: greyed out, kept for a
  // switch back.
  const bool remeshing = object == "mesh" && current.value("improver", "") == "remesh";
  for (const SettingWidget& w : setting_widgets()) {
    if (w.object != object) continue;
    const std::string key(w.key);
    const json value = current.contains(key) ? current[key] : json();
    const bool disabled = remeshing && is_paper_only_mesh_key(w.key);
    ImGui::PushID(key.c_str());
    ImGui::BeginDisabled(disabled);
    switch (w.kind) {
      case WidgetKind::kSwitch:
        draw_switch(state, w, value);
        break;
      case WidgetKind::kWhole:
        draw_whole(state, w, value);
        break;
      case WidgetKind::kNumber:
        draw_number(state, w, value);
        break;
      case WidgetKind::kChoice:
        draw_choice(state, w, value);
        break;
      case WidgetKind::kImprove:
        draw_improve(state, w, value);
        break;
    }
    ImGui::EndDisabled();
    if (disabled)
      tooltip(std::string(w.tooltip) +
                  "\n\nThe remesher does not read this setting (only the few steps of the "
                  "paper's improver that carry the mesh while a parameter moves do). Choose "
                  "Improver: paper to use it; the value is kept.",
              ImGuiHoveredFlags_AllowWhenDisabled);
    ImGui::PopID();
  }
}

}  // namespace zeroset::viewer
