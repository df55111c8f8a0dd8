#pragma once
/// The mesh settings a user gives, and the "mesh" object of a scene file, read by
/// `zeroset mesh` and the viewer's mesh mode and written by the viewer's save-scene:
///
///   "mesh": {"cells": 64, "improve": true, "boundary": "constrain", "grid": "auto",
///            "refine_steps": 12, "curvature": true, "curvature_weight": 8,
///            "singularity": true, "flips": true, "find_singular": true, "crossings": true,
///            "curves": true, "improver": "remesh"}
///
/// "improve" is true or "auto" (until at rest), false or "off", or a number of steps (at
/// most). The other keys are the switches of `zeroset mesh` (docs/meshing.md) and κ_d, the
/// weight of the curvature estimator (docs/algorithms.md, the mesh improver). Every key is
/// optional; missing ones keep their current value. "improver" is "remesh" (the isotropic
/// remesher, zeroset/mesh/remesh.h, the default) or "paper" (the spring–mass improver of the
/// paper, MeshImprover). The command line, scene files and the viewer check these settings with
/// validate_settings below, so each refuses a bad value with the same words.
#include <algorithm>
#include <array>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/remesh.h"

namespace zeroset {

/// Marching cubes cells along the longest side of the clip box.
inline constexpr int kMinMeshCells = 1;
inline constexpr int kMaxMeshCells = 32768;
/// Most improver steps a run may ask for.
inline constexpr int kMaxImproveSteps = 100'000;
/// Most steps placing a vertex onto F = 0 along its grid edge.
inline constexpr int kMaxRefineSteps = 64;
/// Largest κ_d: far beyond it the curvature term alone sets the spring lengths.
inline constexpr double kMaxCurvatureWeight = 1000;

/// Which method improves the marching-cubes mesh.
enum class Improver {
  kPaper,   ///< the spring–mass improver of the paper (MeshImprover)
  kRemesh,  ///< isotropic remeshing with locked features (remesh()), the default
};

/// The keys only the paper's improver reads: its springs' estimators and its Delaunay flips
/// (the remesher sizes edges by one target length and flips towards valence 6). Settings and
/// scene files keep them whichever improver is chosen, so switching back to the paper's finds
/// them; a front end refuses one given explicitly with the remesher, and the viewer greys
/// them out.
inline constexpr std::array<std::string_view, 4> kPaperOnlyMeshKeys = {
    "curvature", "curvature_weight", "singularity", "flips"};
inline bool is_paper_only_mesh_key(std::string_view key) {
  return std::find(kPaperOnlyMeshKeys.begin(), kPaperOnlyMeshKeys.end(), key) !=
         kPaperOnlyMeshKeys.end();
}

/// How a surface is polygonized and improved.
struct MeshSettings {
  int cells = 128;      ///< marching cubes cells along the longest side of the clip box
  bool improve = true;  ///< run the improver after polygonizing
  /// At most this many improver steps; nullopt ("auto"): until at rest, at most the front
  /// end's default (ImproveOptions::max_steps for `zeroset mesh`).
  std::optional<int> max_improve_steps;
  BoundaryMode boundary = BoundaryMode::kConstrained;
  GridMode grid = GridMode::kAuto;  ///< dense, sparse (bricks near the surface) or chosen
  int refine_steps = PolygonizeOptions{}.refine_steps;  ///< 0: linear interpolation
  bool curvature = true;  ///< springs with the curvature estimator (paper eq. 6)
  double curvature_weight = ImproveOptions{}.curvature_weight;  ///< κ_d
  bool singularity = true;    ///< springs with the singularity estimator
  bool flips = true;          ///< Delaunay edge flips
  bool find_singular = true;  ///< Newton's method on ∇F = 0 for singular points
  bool crossings = true;      ///< sheets meet exactly on crossing curves
  bool curves = true;         ///< the singular curves go into the mesh file
  Improver improver = Improver::kRemesh;
};

/// The polygonizer's options for `settings` (bounds, threads and normals are the caller's).
PolygonizeOptions polygonize_options(const MeshSettings& settings);
/// The improver's options for `settings`; max_steps is the step limit, `auto_steps` when the
/// settings say "auto", 0 when they say off (threads are the caller's).
ImproveOptions improve_options(const MeshSettings& settings, int auto_steps);

/// The remesher's options for `settings` (when improve is on; threads are the caller's).
/// The step limit, when the settings give one, bounds its iterations.
RemeshOptions remesh_options(const MeshSettings& settings);

/// Checks cells in [kMinMeshCells, kMaxMeshCells], the improver steps in
/// [0, kMaxImproveSteps], refine_steps in [0, kMaxRefineSteps] and curvature_weight in
/// [0, kMaxCurvatureWeight]. Throws SettingError naming the key as the scene file does ("cells",
/// "improve").
void validate_settings(const MeshSettings& settings);

/// Applies an "improve" value given as text: "auto", "off" or a number of steps (0: off).
/// Throws SettingError (key "improve") for anything else.
void apply_improve(std::string_view text, MeshSettings& settings);

/// "fix" or "constrain"; throws SettingError (key "boundary") for anything else.
BoundaryMode parse_boundary(std::string_view text);
std::string_view to_string(BoundaryMode mode);
/// "paper" or "remesh"; throws SettingError (key "improver") for anything else.
Improver parse_improver(std::string_view text);
std::string_view to_string(Improver improver);
/// "auto", "dense" or "sparse"; throws SettingError (key "grid") for anything else.
GridMode parse_grid(std::string_view text);
std::string_view to_string(GridMode mode);

/// Applies `mesh` (the object above) to `settings`, then validates them. Throws BadInput naming
/// `origin` and the JSON pointer of a malformed or refused entry (e.g. "scene.json:
/// /mesh/cells: must lie in [1, 32768]"). Unknown keys are an error too.
void apply_mesh_settings(const nlohmann::json& mesh, MeshSettings& settings,
                         const std::string& origin);

/// Why apply_mesh_options refuses a key only the paper's improver reads, given with the
/// remesher (a front end adds how to choose the paper's improver in its own words).
inline constexpr std::string_view kPaperOnlyRefusal =
    "sets the paper's improver, but the improver is remesh";

/// Applies the options a user gave, only those given, as an object with the keys above (a
/// front end's flags or keywords: {"cells": 64, "flips": false}), then validates: the one way
/// from a front end's options into the settings. Throws SettingError naming the key, for a
/// value of the wrong type or outside its rule, an unknown key, or a key only the paper's
/// improver reads given with the remesher (why: "sets the paper's improver, but the improver
/// is remesh"; scene files keep such keys, see kPaperOnlyMeshKeys).
void apply_mesh_options(const nlohmann::json& given, MeshSettings& settings);

/// The "mesh" object for `settings`.
nlohmann::json mesh_settings_to_json(const MeshSettings& settings);

}  // namespace zeroset
