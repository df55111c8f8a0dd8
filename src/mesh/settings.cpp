#include "zeroset/mesh/settings.h"

#include <fmt/core.h>

#include <algorithm>
#include <charconv>
#include <cmath>

#include "zeroset/error.h"
#include "zeroset/surface/json_read.h"

namespace zeroset {
namespace {

using nlohmann::json;

std::string improve_rule() {
  return fmt::format("expected auto, off or a number of steps from 0 to {}", kMaxImproveSteps);
}

void set_steps(long long steps, const std::string& text, MeshSettings& m) {
  if (steps < 0 || steps > kMaxImproveSteps) throw SettingError("improve", text, improve_rule());
  m.improve = steps > 0;
  if (steps > 0) m.max_improve_steps = static_cast<int>(steps);
}

}  // namespace

void validate_settings(const MeshSettings& m) {
  if (m.cells < kMinMeshCells || m.cells > kMaxMeshCells)
    throw SettingError("cells", std::to_string(m.cells),
                       fmt::format("must lie in [{}, {}]", kMinMeshCells, kMaxMeshCells));
  if (m.max_improve_steps && (*m.max_improve_steps < 0 || *m.max_improve_steps > kMaxImproveSteps))
    throw SettingError("improve", std::to_string(*m.max_improve_steps), improve_rule());
}

void apply_improve(std::string_view text, MeshSettings& m) {
  const std::string t(text);
  if (text == "auto") {
    m.improve = true;
    m.max_improve_steps.reset();
    return;
  }
  if (text == "off") {
    m.improve = false;
    return;
  }
  long long steps = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), steps);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size())
    throw SettingError("improve", t, improve_rule());
  set_steps(steps, t, m);
}

BoundaryMode parse_boundary(std::string_view text) {
  if (text == "fix") return BoundaryMode::kFixed;
  if (text == "constrain") return BoundaryMode::kConstrained;
  throw SettingError("boundary", std::string(text), "expected fix or constrain");
}

std::string_view to_string(BoundaryMode mode) {
  return mode == BoundaryMode::kFixed ? "fix" : "constrain";
}

void apply_mesh_settings(const json& mesh, MeshSettings& settings, const std::string& origin) {
  const std::string base = "/mesh";
  if (!mesh.is_object()) json_read::fail(origin, base, "expected an object");
  json_read::known_keys(mesh, {"cells", "improve", "boundary"}, origin, base);
  MeshSettings m = settings;
  try {
    // The types here; the ranges are validate_settings' (the same for every entry point).
    if (mesh.contains("cells")) {
      const json& v = mesh["cells"];
      const double c = v.is_number() ? v.get<double>() : std::nan("");
      if (!(c == std::floor(c))) json_read::fail(origin, base + "/cells", "expected a whole number");
      m.cells = static_cast<int>(std::clamp(c, -1e9, 1e9));  // far outside the rule stays so
    }
    if (mesh.contains("improve")) {
      const json& v = mesh["improve"];
      if (v.is_boolean())
        apply_improve(v.get<bool>() ? "auto" : "off", m);
      else if (v.is_string())
        apply_improve(v.get<std::string>(), m);
      else if (v.is_number_integer())
        set_steps(v.get<long long>(), std::to_string(v.get<long long>()), m);
      else
        json_read::fail(origin, base + "/improve",
                        "expected true, false, \"auto\", \"off\" or a number of steps");
    }
    if (mesh.contains("boundary"))
      m.boundary =
          parse_boundary(json_read::string(mesh["boundary"], origin, base + "/boundary"));
    validate_settings(m);
  } catch (const SettingError& e) {
    json_read::fail(origin, base + "/" + e.key(), e.why());
  }
  settings = m;
}

json mesh_settings_to_json(const MeshSettings& m) {
  json improve = m.improve;
  if (m.improve && m.max_improve_steps) improve = *m.max_improve_steps;
  return {{"cells", m.cells}, {"improve", improve}, {"boundary", std::string(to_string(m.boundary))}};
}

}  // namespace zeroset
