#include "panel.h"

#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "settings_panel.h"
#include "zeroset/expr/field.h"
#include "zeroset/surface/catalog.h"

namespace zeroset::viewer {
namespace {

const ImVec4 kErrorColor(0.95f, 0.35f, 0.3f, 1.0f);
const ImVec4 kDimColor(0.65f, 0.67f, 0.72f, 1.0f);
const ImVec4 kNoteColor(0.95f, 0.75f, 0.3f, 1.0f);

// ImGui aborts on slider bounds beyond ±DBL_MAX/2 (±FLT_MAX/2 for floats), and computes
// max − min: every bound is clamped to a finite span first, those of doubles to the parameter
// limit, those of floats well inside the float range.
double slider_bound(double v) {
  return std::isnan(v) ? 0.0 : std::clamp(v, -kMaxParameterMagnitude, kMaxParameterMagnitude);
}
// Bounds of one sign at least three decades apart.
bool uses_log_slider(double lo, double hi) {
  return (lo > 0 && hi >= 1000 * lo) || (hi < 0 && lo <= 1000 * hi);
}
float slider_bound_float(double v) {
  constexpr double kFloatBound = 1e30;
  return static_cast<float>(std::isnan(v) ? 0.0 : std::clamp(v, -kFloatBound, kFloatBound));
}

void help_marker(const char* text) {
  ImGui::SameLine();
  ImGui::TextDisabled("(?)");
  if (ImGui::IsItemHovered()) {
    ImGui::BeginTooltip();
    ImGui::PushTextWrapPos(ImGui::GetFontSize() * 28);
    ImGui::TextUnformatted(text);
    ImGui::PopTextWrapPos();
    ImGui::EndTooltip();
  }
}

void surface_section(ViewerState& state, PanelState& panel) {
  if (!ImGui::CollapsingHeader("Surface", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const Surface& s = state.surface();
  const std::string current = s.name.empty() ? std::string("(typed equation)") : s.name;
  if (ImGui::BeginCombo("Catalog", current.c_str())) {
    for (const CatalogEntry& e : catalog()) {
      const std::string label = e.name + "  -  " + e.title;
      if (ImGui::Selectable(label.c_str(), e.name == s.name)) state.select_catalog(e.name);
    }
    ImGui::EndCombo();
  }

  // The field follows the state (catalog, scripts) unless the user is editing it.
  if (panel.shown_equation != state.equation_text()) {
    panel.equation = state.equation_text();
    panel.shown_equation = state.equation_text();
  }
  ImGui::TextUnformatted("Equation");
  help_marker(
      "Type F(x, y, z) or lhs = rhs. Local definitions first, separated by ';' or new "
      "lines. Other names are parameters. Enter applies, Ctrl+Enter starts a new line.");
  if (panel.mono_font) ImGui::PushFont(panel.mono_font);
  const float lines = static_cast<float>(
      std::clamp<long>(std::count(panel.equation.begin(), panel.equation.end(), '\n') + 1, 2, 8));
  const bool entered = ImGui::InputTextMultiline(
      "##equation", &panel.equation, ImVec2(-1, (lines + 0.6f) * ImGui::GetTextLineHeight()),
      ImGuiInputTextFlags_EnterReturnsTrue | ImGuiInputTextFlags_CtrlEnterForNewLine);
  if (panel.mono_font) ImGui::PopFont();
  if (ImGui::Button("Apply") || entered) state.set_equation(panel.equation);
  const std::string& error = state.equation_error();
  if (!error.empty()) {
    // Unwrapped, so the caret stays under its column; long lines scroll sideways.
    if (panel.mono_font) ImGui::PushFont(panel.mono_font);
    const float lines_shown = static_cast<float>(std::count(error.begin(), error.end(), '\n') + 1);
    const ImGuiStyle& style = ImGui::GetStyle();
    const float height = lines_shown * ImGui::GetTextLineHeightWithSpacing() +
                         2 * style.WindowPadding.y + style.ScrollbarSize;
    ImGui::BeginChild("diagnostics", ImVec2(0, height), true, ImGuiWindowFlags_HorizontalScrollbar);
    ImGui::PushStyleColor(ImGuiCol_Text, kErrorColor);
    ImGui::TextUnformatted(error.c_str());
    ImGui::PopStyleColor();
    ImGui::EndChild();
    if (panel.mono_font) ImGui::PopFont();
  }

  // Copies: an action may change the ranges while we walk them.
  const std::vector<ParamSpec> ranges = state.surface().ranges;
  if (!ranges.empty()) {
    ImGui::Separator();
    ImGui::TextUnformatted("Parameters");
  }
  const std::vector<double> values = state.surface().field.parameter_values();
  for (size_t i = 0; i < ranges.size(); ++i) {
    const ParamSpec& r = ranges[i];  // one per parameter, in the field's order
    ImGui::PushID(r.name.c_str());
    // A value typed into the slider (Ctrl+click) or the range fields goes to the state as it
    // is: one beyond the parameter limit is refused there, with the reason in the status line.
    double v = values[i], lo = r.min, hi = r.max;
    const double slider_lo = slider_bound(lo), slider_hi = slider_bound(hi);
    // A range over decades of one sign gets a logarithmic slider: a linear one would give the
    // first decades a few pixels (the Kummer family runs from 0.34 to 1.28e6).
    const bool log_scale = uses_log_slider(slider_lo, slider_hi);
    if (ImGui::SliderScalar(r.name.c_str(), ImGuiDataType_Double, &v, &slider_lo, &slider_hi,
                            "%.5g", log_scale ? ImGuiSliderFlags_Logarithmic : 0))
      state.set_parameter(r.name, v);
    if (ImGui::TreeNode("range")) {
      ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x * 0.4f);
      ImGui::InputDouble("min", &lo, 0, 0, "%.5g");
      if (ImGui::IsItemDeactivatedAfterEdit()) state.set_parameter_range(r.name, lo, hi);
      ImGui::SameLine();
      ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x * 0.6f);
      ImGui::InputDouble("max", &hi, 0, 0, "%.5g");
      if (ImGui::IsItemDeactivatedAfterEdit()) state.set_parameter_range(r.name, lo, hi);
      ImGui::TreePop();
    }
    ImGui::PopID();
  }
  if (ranges.empty()) return;

  const Animation& a = state.animation();
  const std::string animated = a.parameter.empty() ? ranges.front().name : a.parameter;
  ImGui::SetNextItemWidth(90);
  if (ImGui::BeginCombo("##animated", animated.c_str())) {
    for (const ParamSpec& r : ranges)
      if (ImGui::Selectable(r.name.c_str(), r.name == animated))
        state.set_animation_parameter(r.name);
    ImGui::EndCombo();
  }
  ImGui::SameLine();
  if (ImGui::Button(a.is_playing ? "Pause" : "Play")) {
    if (a.is_playing)
      state.pause();
    else if (state.has_keyframes())
      state.play();  // the keyframes, not one parameter
    else
      state.play(animated);
  }
  ImGui::SameLine();
  bool loop = a.loop;
  if (ImGui::Checkbox("Loop", &loop)) state.set_loop(loop);
  double speed = a.speed;
  const double speed_min = 0.005, speed_max = 2.0;
  if (ImGui::SliderScalar("Speed", ImGuiDataType_Double, &speed, &speed_min, &speed_max, "%.3f",
                          ImGuiSliderFlags_Logarithmic))
    state.set_speed(speed);
  help_marker("Ranges per second: 0.1 sweeps the parameter's range in 10 seconds.");
}

void floaters_settings(ViewerState& state) {
  const ViewerStats st = state.stats();
  ImGui::Text("%zu floaters   %.0f steps/s   step %zu", st.floater_count, st.steps_per_second,
              st.floater_steps);
  ImGui::Text("residual |F|/|grad F|: median %.1e, max %.1e", st.median_residual, st.max_residual);
  ImGui::Text("sigma-hat %.4g   %s", st.nominal_radius, st.converged ? "at rest" : "moving");
  const bool off_surface = st.floater_count == 0 || !(st.median_residual <= st.nominal_radius);
  if (st.floater_steps > 0 && off_surface)
    ImGui::TextColored(kDimColor,
                       "off F = 0: still finding the surface, or it has no point\n"
                       "inside the clip (or F is undefined there)");

  draw_setting_widgets(state, "floaters");
  if (ImGui::Button("Reset floaters")) state.reset_floaters();

  DisplaySettings d = state.display();
  bool display_changed = false;
  int draw = d.draw_points ? 1 : 0;
  display_changed |= ImGui::RadioButton("Disks", &draw, 0);
  ImGui::SameLine();
  display_changed |= ImGui::RadioButton("Points", &draw, 1);
  d.draw_points = draw == 1;
  if (d.draw_points) {
    float size = static_cast<float>(d.point_size_px);
    if (ImGui::SliderFloat("Point size", &size, 1, 16, "%.0f px")) {
      d.point_size_px = size;
      display_changed = true;
    }
  } else {
    float scale = static_cast<float>(d.disk_scale);
    if (ImGui::SliderFloat("Disk size", &scale, 0.1f, 2.0f, "%.2f x sigma")) {
      d.disk_scale = scale;
      display_changed = true;
    }
  }
  if (display_changed) state.set_display(d);
}

void mesh_settings(ViewerState& state) {
  const ViewerStats st = state.stats();
  const auto frame = state.mesh();
  ImGui::Text("%zu vertices, %zu triangles", st.mesh_vertices, st.mesh_triangles);
  if (frame) {
    // Whether the last parameter change carried the mesh or rebuilt it (and why).
    ImGui::TextWrapped("%s, %.1f updates/s", st.mesh_update.c_str(), st.mesh_updates_per_second);
    ImGui::Text("marching cubes %.0f ms", 1000 * frame->polygonize.seconds_total);
    const CrossingStats& c = frame->crossings;
    if (c.crossing_curves > 0 && c.failure.empty())
      ImGui::Text("%d crossing curve%s joined exactly", c.crossing_curves,
                  c.crossing_curves == 1 ? "" : "s");
    if (!c.failure.empty()) ImGui::TextWrapped("Crossings left rounded: %s", c.failure.c_str());
    if (frame->improver_steps > 0) {
      ImGui::Text("improver step %d%s", frame->improver_steps,
                  frame->is_final ? (frame->improve.converged ? ", converged" : ", done") : "");
      ImGui::Text("largest move %.2g edge lengths", frame->improve.max_move);
      ImGui::Text("%zu singular points found and held", frame->improve.singular_points.size());
    }
  }
  if (st.is_busy) ImGui::TextColored(kDimColor, "working...");

  draw_setting_widgets(state, "mesh");
  DisplaySettings d = state.display();
  if (ImGui::Checkbox("Wireframe", &d.wireframe)) state.set_display(d);
}

void raytrace_info(ViewerState& state) {
  const ViewerStats st = state.stats();
  if (st.preview_divisor == 0)
    ImGui::TextUnformatted("tracing...");
  else if (st.preview_divisor == 1)
    ImGui::Text("full resolution, %.2f s", st.preview_seconds);
  else
    ImGui::Text("1/%d resolution, %.2f s, refining...", st.preview_divisor, st.preview_seconds);
}

// A small square of an overlay colour (linear RGB) and a label after it.
void swatch(const Color& c, const std::string& label) {
  auto encode = [](double v) {
    return static_cast<float>(std::pow(std::clamp(v, 0.0, 1.0), 1 / 2.2));
  };
  const float h = ImGui::GetTextLineHeight();
  ImGui::ColorButton(label.c_str(), ImVec4(encode(c.x()), encode(c.y()), encode(c.z()), 1),
                     ImGuiColorEditFlags_NoTooltip | ImGuiColorEditFlags_NoDragDrop, ImVec2(h, h));
  ImGui::SameLine();
  ImGui::TextUnformatted(label.c_str());
}

void singular_section(ViewerState& state) {
  DisplaySettings d = state.display();
  if (ImGui::Checkbox("Singular set (S)", &d.show_singular)) state.set_display(d);
  help_marker(
      "Where grad F = 0 on the surface: curves as thin tubes, special points as small "
      "spheres, in the colours listed below, hidden where the surface lies in front. "
      "Found again whenever the equation, a parameter or the clip changes.");
  if (!d.show_singular) return;
  const auto frame = state.singular();
  if (!frame) {
    ImGui::TextColored(kDimColor, "searching...");
    return;
  }
  if (!frame->summary.empty()) ImGui::TextWrapped("%s", frame->summary.c_str());
  if (!frame->note.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, kNoteColor);
    ImGui::TextWrapped("%s", frame->note.c_str());
    ImGui::PopStyleColor();
  }
  // A legend of the kinds present, in the overlay's colours.
  const SingularOverlay style;
  for (const CurveKind k : {CurveKind::kCrossing, CurveKind::kIsolated, CurveKind::kDegenerate})
    if (frame->set.count(k) > 0) swatch(style.color(k), std::string(to_string(k)) + " curves");
  for (const SingularPointKind k :
       {SingularPointKind::kNode, SingularPointKind::kTriple, SingularPointKind::kPinch,
        SingularPointKind::kDegenerate, SingularPointKind::kClipEnd})
    if (!frame->set.points_of(k).empty())
      swatch(style.color(k), k == SingularPointKind::kNode ? std::string("nodes")
                                                           : std::string(to_string(k)) + " points");
  if (!state.singular_is_current())
    ImGui::TextColored(kDimColor, "updating...");
  else
    ImGui::TextColored(kDimColor, "found in %.0f ms", 1000 * frame->seconds);
}

void mode_section(ViewerState& state) {
  if (!ImGui::CollapsingHeader("Mode", ImGuiTreeNodeFlags_DefaultOpen)) return;
  int mode = static_cast<int>(state.mode());
  bool changed = ImGui::RadioButton("Floaters", &mode, static_cast<int>(Mode::kFloaters));
  ImGui::SameLine();
  changed |= ImGui::RadioButton("Mesh", &mode, static_cast<int>(Mode::kMesh));
  ImGui::SameLine();
  changed |= ImGui::RadioButton("Ray traced", &mode, static_cast<int>(Mode::kRaytrace));
  if (changed) state.set_mode(static_cast<Mode>(mode));
  switch (state.mode()) {
    case Mode::kFloaters:
      floaters_settings(state);
      break;
    case Mode::kMesh:
      mesh_settings(state);
      break;
    case Mode::kRaytrace:
      raytrace_info(state);
      break;
  }
  ImGui::Separator();
  singular_section(state);
  ImGui::TextColored(kDimColor, "drawing takes %.0f ms a frame", 1000 * state.stats().draw_seconds);
}

void clip_section(ViewerState& state) {
  if (!ImGui::CollapsingHeader("Clip")) return;
  Clip clip = state.surface().clip;
  bool changed = false;
  const float reach = slider_bound_float(3 * state.surface().scene_radius());
  for (size_t i = 0; i < clip.spheres.size(); ++i) {
    ImGui::PushID(static_cast<int>(i));
    SphereClip& s = clip.spheres[i];
    ImGui::Text("sphere %zu", i + 1);
    ImGui::SameLine();
    if (ImGui::SmallButton("remove")) {
      clip.spheres.erase(clip.spheres.begin() + static_cast<long>(i));
      changed = true;
      ImGui::PopID();
      break;
    }
    float r = static_cast<float>(s.radius);
    ImGui::SliderFloat("radius", &r, 0.01f, reach, "%.3f");
    if (ImGui::IsItemDeactivatedAfterEdit()) {
      if (std::isfinite(r) && r > 0) {
        s.radius = r;
        changed = true;
      } else {
        state.set_status("clip: a sphere's radius must be a positive finite number", true);
      }
    }
    float c[3] = {static_cast<float>(s.center.x()), static_cast<float>(s.center.y()),
                  static_cast<float>(s.center.z())};
    ImGui::InputFloat3("center", c, "%.3f");
    if (ImGui::IsItemDeactivatedAfterEdit()) {
      if (Vec3(c[0], c[1], c[2]).allFinite()) {
        s.center = Vec3(c[0], c[1], c[2]);
        changed = true;
      } else {
        state.set_status("clip: a sphere's centre must be finite", true);
      }
    }
    ImGui::PopID();
  }
  for (size_t i = 0; i < clip.planes.size() && !changed; ++i) {
    ImGui::PushID(static_cast<int>(1000 + i));
    HalfSpaceClip& p = clip.planes[i];
    ImGui::Text("half space %zu: n.x <= d", i + 1);
    ImGui::SameLine();
    if (ImGui::SmallButton("remove")) {
      clip.planes.erase(clip.planes.begin() + static_cast<long>(i));
      changed = true;
      ImGui::PopID();
      break;
    }
    float n[3] = {static_cast<float>(p.normal.x()), static_cast<float>(p.normal.y()),
                  static_cast<float>(p.normal.z())};
    ImGui::InputFloat3("n", n, "%.3f");
    if (ImGui::IsItemDeactivatedAfterEdit()) {
      const Vec3 v(n[0], n[1], n[2]);
      if (v.allFinite() && v.norm() > 0) {
        p.normal = v.normalized();
        changed = true;
      } else {
        state.set_status("clip: a plane's normal must not be zero", true);
      }
    }
    float d = static_cast<float>(p.offset);
    ImGui::SliderFloat("d", &d, -reach, reach, "%.3f");
    if (ImGui::IsItemDeactivatedAfterEdit() && std::isfinite(d)) {
      p.offset = d;
      changed = true;
    }
    ImGui::PopID();
  }
  if (ImGui::Button("Add sphere")) {
    clip.spheres.push_back({state.surface().bounds().center(), state.surface().scene_radius()});
    changed = true;
  }
  ImGui::SameLine();
  if (ImGui::Button("Add half space")) {
    clip.planes.push_back({Vec3::UnitZ(), state.surface().scene_radius()});
    changed = true;
  }
  if (changed) state.set_clip(clip);
}

void view_section(ViewerState& state) {
  if (!ImGui::CollapsingHeader("View")) return;
  if (ImGui::Button("Reset view (R)")) state.reset_view();
  Camera cam = state.camera();
  ImGui::Text("azimuth %.1f, elevation %.1f, distance %.3g", cam.azimuth_deg, cam.elevation_deg,
              cam.distance);
  bool ortho = cam.is_orthographic();
  if (ImGui::Checkbox("Orthographic (parallel rays)", &ortho)) {
    cam.projection = ortho ? Projection::orthographic : Projection::perspective;
    state.set_camera(cam);
  }
  if (ortho) {
    const double radius = state.surface().scene_radius();
    float height = static_cast<float>(cam.view_height(radius));
    if (ImGui::SliderFloat("Visible height", &height, static_cast<float>(0.02 * radius),
                           static_cast<float>(100 * radius), "%.3g",
                           ImGuiSliderFlags_Logarithmic)) {
      cam.ortho_height = height;
      state.set_camera(cam);
    }
  } else {
    float fov = static_cast<float>(cam.fov_deg);
    if (ImGui::SliderFloat("Field of view", &fov, 5, 90, "%.0f deg")) {
      cam.fov_deg = fov;
      state.set_camera(cam);
    }
  }
  bool follow = state.lights_follow_camera();
  if (ImGui::Checkbox("Lights follow the camera", &follow)) state.set_lights_follow_camera(follow);
  RenderOptions look = state.look();
  auto edit = [](const char* label, Color& c) {
    float f[3] = {static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())};
    if (!ImGui::ColorEdit3(label, f)) return false;
    c = Color(f[0], f[1], f[2]);
    return true;
  };
  bool changed = edit("Front", look.front.diffuse);
  changed |= edit("Back", look.back.diffuse);
  changed |= edit("Background", look.background);
  if (changed) state.set_look(look);
}

void files_section(ViewerState& state, PanelState& panel) {
  if (!ImGui::CollapsingHeader("Save")) return;
  auto row = [](const char* id, std::string& path, const char* button) {
    ImGui::PushID(id);
    ImGui::SetNextItemWidth(ImGui::GetContentRegionAvail().x - 90);
    ImGui::InputText("##path", &path);
    ImGui::SameLine();
    const bool pressed = ImGui::Button(button, ImVec2(82, 0));
    ImGui::PopID();
    return pressed;
  };
  if (row("scene", panel.scene_path, "Scene")) state.save_scene(panel.scene_path);
  if (row("shot", panel.screenshot_path, "Screenshot")) panel.wants_screenshot = true;
  if (state.mode() == Mode::kMesh && row("mesh", panel.mesh_path, "Mesh"))
    state.save_mesh(panel.mesh_path);
  if (state.mode() == Mode::kFloaters && row("floaters", panel.floaters_path, "Floaters"))
    state.save_floaters(panel.floaters_path);
  if (row("pov", panel.pov_path, "POV-Ray")) state.save_pov(panel.pov_path);
}

void command_section(ViewerState& state, PanelState& panel) {
  if (!ImGui::CollapsingHeader("Command")) return;
  ImGui::SetNextItemWidth(-1);
  if (ImGui::InputTextWithHint("##command", "e.g. param mu 2   (Enter runs it)", &panel.command,
                               ImGuiInputTextFlags_EnterReturnsTrue)) {
    if (state.command(panel.command)) panel.command.clear();
    ImGui::SetKeyboardFocusHere(-1);
  }
}

void help_section() {
  if (!ImGui::CollapsingHeader("Controls")) return;
  ImGui::TextUnformatted(
      "left drag       orbit\n"
      "right drag      pan (also shift + left drag)\n"
      "wheel           zoom\n"
      "R               reset view\n"
      "space           play / pause the animation\n"
      "1 / 2 / 3       floaters / mesh / ray traced\n"
      "W               wireframe (mesh)\n"
      "S               singular set on / off\n"
      "P               disks / points (floaters)\n"
      "H               hide / show this panel\n"
      "F12             screenshot\n"
      "Ctrl+Q          quit");
}

}  // namespace

void draw_panel(ViewerState& state, PanelState& panel, float height) {
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(kPanelWidth, height));
  ImGui::Begin("zeroset view", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  ImGui::PushItemWidth(-110);
  const StatusLine& status = state.status();
  if (!status.text.empty()) {
    ImGui::PushStyleColor(ImGuiCol_Text, status.is_error ? kErrorColor : kDimColor);
    ImGui::TextWrapped("%s", status.text.c_str());
    ImGui::PopStyleColor();
  }
  // The field's warning stays in view while it holds, whatever the last status says.
  if (const std::string& warning = state.field_warning();
      !warning.empty() && status.text != "warning: " + warning) {
    ImGui::PushStyleColor(ImGuiCol_Text, kErrorColor);
    ImGui::TextWrapped("warning: %s", warning.c_str());
    ImGui::PopStyleColor();
  }
  surface_section(state, panel);
  keyframes_section(state, panel);
  mode_section(state);
  clip_section(state);
  view_section(state);
  files_section(state, panel);
  command_section(state, panel);
  help_section();
  ImGui::PopItemWidth();
  ImGui::End();
}

}  // namespace zeroset::viewer
