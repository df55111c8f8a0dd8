#include "zeroset/mesh/settings.h"

#include <fmt/core.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
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
  if (m.refine_steps < 0 || m.refine_steps > kMaxRefineSteps)
    throw SettingError("refine_steps", std::to_string(m.refine_steps),
                       fmt::format("must lie in [0, {}]", kMaxRefineSteps));
  if (!(m.curvature_weight >= 0 && m.curvature_weight <= kMaxCurvatureWeight))
    throw SettingError("curvature_weight", fmt::format("{}", m.curvature_weight),
                       fmt::format("must lie in [0, {:g}]", kMaxCurvatureWeight));
}

PolygonizeOptions polygonize_options(const MeshSettings& m) {
  PolygonizeOptions o;
  o.cells = m.cells;
  o.mode = m.grid;
  o.refine_steps = m.refine_steps;
  return o;
}

ImproveOptions improve_options(const MeshSettings& m, int auto_steps) {
  ImproveOptions o;
  o.max_steps = m.improve ? m.max_improve_steps.value_or(auto_steps) : 0;
  o.boundary = m.boundary;
  o.use_curvature = m.curvature;
  o.curvature_weight = m.curvature_weight;
  o.use_singularity = m.singularity;
  o.flip_edges = m.flips;
  o.find_singular_points = m.find_singular;
  return o;
}

RemeshOptions remesh_options(const MeshSettings& m) {
  RemeshOptions o;
  if (m.max_improve_steps) o.max_iterations = std::min(o.max_iterations, *m.max_improve_steps);
  o.boundary = m.boundary;
  o.find_singular_points = m.find_singular;
  return o;
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

Improver parse_improver(std::string_view text) {
  if (text == "paper") return Improver::kPaper;
  if (text == "remesh") return Improver::kRemesh;
  throw SettingError("improver", std::string(text), "expected paper or remesh");
}

std::string_view to_string(Improver improver) {
  return improver == Improver::kRemesh ? "remesh" : "paper";
}

GridMode parse_grid(std::string_view text) {
  if (text == "auto") return GridMode::kAuto;
  if (text == "dense") return GridMode::kDense;
  if (text == "sparse") return GridMode::kSparse;
  throw SettingError("grid", std::string(text), "expected auto, dense or sparse");
}

std::string_view to_string(GridMode mode) {
  switch (mode) {
    case GridMode::kDense:
      return "dense";
    case GridMode::kSparse:
      return "sparse";
    case GridMode::kAuto:
      break;
  }
  return "auto";
}

namespace {

constexpr std::array<const char*, 13> kMeshKeys = {
    "cells",     "improve",          "boundary",    "grid",  "refine_steps",
    "curvature", "curvature_weight", "singularity", "flips", "find_singular",
    "crossings", "curves",           "improver"};

int whole_number(const json& mesh, const char* key) {
  const json& v = mesh[key];
  const double c = v.is_number() ? v.get<double>() : std::nan("");
  if (!(c == std::floor(c))) throw SettingError(key, v.dump(), "expected a whole number");
  // Far outside the rule stays so (validate_settings says the rule).
  return static_cast<int>(std::clamp(c, -1e9, 1e9));
}

// Reads the entries of a "mesh" object into `m` and validates the result: the one reader of
// mesh settings, behind scene files, flags and keywords alike. SettingError names the key.
void read_mesh_object(const json& mesh, MeshSettings& m) {
  for (auto it = mesh.begin(); it != mesh.end(); ++it) {
    const std::string& key = it.key();  // not a structured binding: the lambda captures it
    if (std::none_of(kMeshKeys.begin(), kMeshKeys.end(), [&](const char* k) { return key == k; }))
      throw SettingError(key, it.value().dump(), "is not a mesh setting");
  }
  if (mesh.contains("cells")) m.cells = whole_number(mesh, "cells");
  if (mesh.contains("improve")) {
    const json& v = mesh["improve"];
    if (v.is_boolean())
      apply_improve(v.get<bool>() ? "auto" : "off", m);
    else if (v.is_string())
      apply_improve(v.get<std::string>(), m);
    else if (v.is_number_integer())
      set_steps(v.get<long long>(), std::to_string(v.get<long long>()), m);
    else
      throw SettingError("improve", v.dump(),
                         "expected true, false, \"auto\", \"off\" or a number of steps");
  }
  const auto text = [&](const char* key) { return json_read::setting_string(mesh[key], key); };
  if (mesh.contains("boundary")) m.boundary = parse_boundary(text("boundary"));
  if (mesh.contains("improver")) m.improver = parse_improver(text("improver"));
  if (mesh.contains("grid")) m.grid = parse_grid(text("grid"));
  if (mesh.contains("refine_steps")) m.refine_steps = whole_number(mesh, "refine_steps");
  if (mesh.contains("curvature_weight"))
    m.curvature_weight = json_read::setting_number(mesh["curvature_weight"], "curvature_weight");
  for (auto [key, flag] :
       {std::pair{"curvature", &m.curvature}, std::pair{"singularity", &m.singularity},
        std::pair{"flips", &m.flips}, std::pair{"find_singular", &m.find_singular},
        std::pair{"crossings", &m.crossings}, std::pair{"curves", &m.curves}})
    if (mesh.contains(key)) *flag = json_read::setting_boolean(mesh[key], key);
  validate_settings(m);
}

}  // namespace

void apply_mesh_settings(const json& mesh, MeshSettings& settings, const std::string& origin) {
  const std::string base = "/mesh";
  if (!mesh.is_object()) json_read::fail(origin, base, "expected an object");
  json_read::known_keys(mesh, kMeshKeys, origin, base);
  MeshSettings m = settings;
  try {
    read_mesh_object(mesh, m);
  } catch (const SettingError& e) {
    json_read::fail(origin, base + "/" + e.key(), e.why());
  }
  settings = m;
}

void apply_mesh_options(const json& given, MeshSettings& settings) {
  MeshSettings m = settings;
  read_mesh_object(given, m);
  if (m.improver == Improver::kRemesh)
    for (std::string_view key : kPaperOnlyMeshKeys)
      if (given.contains(key))
        throw SettingError(std::string(key), given[std::string(key)].dump(),
                           std::string(kPaperOnlyRefusal));
  settings = m;
}

json mesh_settings_to_json(const MeshSettings& m) {
  json improve = m.improve;
  if (m.improve && m.max_improve_steps) improve = *m.max_improve_steps;
  return {{"cells", m.cells},
          {"improve", improve},
          {"boundary", std::string(to_string(m.boundary))},
          {"grid", std::string(to_string(m.grid))},
          {"refine_steps", m.refine_steps},
          {"curvature", m.curvature},
          {"curvature_weight", m.curvature_weight},
          {"singularity", m.singularity},
          {"flips", m.flips},
          {"find_singular", m.find_singular},
          {"crossings", m.crossings},
          {"curves", m.curves},
          {"improver", std::string(to_string(m.improver))}};
}

}  // namespace zeroset
