#pragma once
/// The mesh settings a user gives, and the "mesh" object of a scene file, read by
/// `zeroset mesh` and the viewer's mesh mode and written by the viewer's save-scene:
///
///   "mesh": {"cells": 64, "improve": true, "boundary": "constrain"}
///
/// "improve" is true or "auto" (until at rest), false or "off", or a number of steps (at
/// most). Every key is optional; missing ones keep their current value. The command line,
/// scene files and the viewer check these settings with validate_settings below, so each
/// refuses a bad value with the same words.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "zeroset/mesh/improve.h"

namespace zeroset {

/// Marching cubes cells along the longest side of the clip box.
inline constexpr int kMinMeshCells = 1;
inline constexpr int kMaxMeshCells = 32768;
/// Most improver steps a run may ask for.
inline constexpr int kMaxImproveSteps = 100'000;

/// How a surface is polygonized and improved.
struct MeshSettings {
  int cells = 128;       ///< marching cubes cells along the longest side of the clip box
  bool improve = true;   ///< run the improver after polygonizing
  /// At most this many improver steps; nullopt ("auto"): until at rest, at most the front
  /// end's default (ImproveOptions::max_steps for `zeroset mesh`).
  std::optional<int> max_improve_steps;
  BoundaryMode boundary = BoundaryMode::kConstrained;
};

/// Checks cells in [kMinMeshCells, kMaxMeshCells] and the improver steps in
/// [0, kMaxImproveSteps]. Throws SettingError naming the key as the scene file does ("cells",
/// "improve").
void validate_settings(const MeshSettings& settings);

/// Applies an "improve" value given as text: "auto", "off" or a number of steps (0: off).
/// Throws SettingError (key "improve") for anything else.
void apply_improve(std::string_view text, MeshSettings& settings);

/// "fix" or "constrain"; throws SettingError (key "boundary") for anything else.
BoundaryMode parse_boundary(std::string_view text);
std::string_view to_string(BoundaryMode mode);

/// Applies `mesh` (the object above) to `settings`, then validates them. Throws BadInput naming
/// `origin` and the JSON pointer of a malformed or refused entry (e.g. "scene.json:
/// /mesh/cells: must lie in [1, 32768]"). Unknown keys are an error too.
void apply_mesh_settings(const nlohmann::json& mesh, MeshSettings& settings,
                         const std::string& origin);

/// The "mesh" object for `settings`.
nlohmann::json mesh_settings_to_json(const MeshSettings& settings);

}  // namespace zeroset
