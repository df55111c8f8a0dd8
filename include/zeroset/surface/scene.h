#pragma once
/// Surfaces from the command line or a scene file (JSON).
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "zeroset/surface/surface.h"

namespace zeroset {

/// A surface plus the settings of each stage (objects "render", "floaters", "mesh",
/// "animation" in the file, read by those stages; unknown keys are kept).
struct Scene {
  Surface surface;
  nlohmann::json settings = nlohmann::json::object();
};

/// Overrides applied on top of a surface's defaults.
struct SurfaceOverrides {
  std::map<std::string, double> params;  ///< --param k=v
  std::vector<std::string> clip_specs;   ///< --clip specs; non-empty replaces the default clip
};

/// Resolves a SURFACE argument: a catalog name, a scene file (a path ending in .json, or a
/// SURFER file ending in .jsurf, read by read_jsurf) or an equation in the surface language.
/// Applies overrides, then checks that every parameter has a value. An equation given without
/// --clip gets a default clip sphere when it is a polynomial whose surface is provably bounded
/// (its top-degree part is definite); otherwise it stays unclipped, and stages that need a
/// volume ask for --clip. Throws ParseError, InvalidArgument or IoError (all BadInput).
Scene resolve_scene(const std::string& spec, const SurfaceOverrides& overrides = {});
inline Surface resolve_surface(const std::string& spec, const SurfaceOverrides& o = {}) {
  return resolve_scene(spec, o).surface;
}

/// Builds a surface from an equation (no catalog entry). Parameters get no values.
Surface surface_from_equation(const std::string& equation);

nlohmann::json scene_to_json(const Scene& scene);
/// The scene format's version, the value of "zeroset_scene" (optional in a file; other values
/// are refused).
inline constexpr int kSceneVersion = 1;
/// Throws BadInput with the JSON path of the offending entry. Top-level keys it does not know
/// are moved (not copied) into Scene::settings.
Scene scene_from_json(nlohmann::json j, const std::string& origin);
/// Reads a scene file: JSON, or a SURFER .jsurf file (by its extension; zeroset/surface/jsurf.h).
/// JSON is read within json_read's limits (size, depth, no repeated keys, no NUL byte).
Scene read_scene(const std::string& path);
/// Written atomically (temporary file + rename).
void write_scene(const Scene& scene, const std::string& path);

}  // namespace zeroset
