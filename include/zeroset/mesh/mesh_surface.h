#pragma once
/// The mesh recipe, one for every front end (docs/meshing.md, "The pipeline"): the field
/// survey, marching cubes cut at the clip, the crossings along singular curves (which find the
/// singular set), then the isotropic remesher or the paper's spring–mass improver, and the
/// checks of the result. `zeroset mesh`, the viewer's mesh mode, Python's Surface.mesh, the
/// benchmarks and the examples all call mesh_surface(); none chains the stages itself. Its
/// statistics serialise through MeshResult::to_json(), the `--stats` file of `zeroset mesh`
/// and the dictionary Python returns.
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "zeroset/mesh/adjacency.h"
#include "zeroset/mesh/crossings.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/mesh.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"
#include "zeroset/mesh/remesh.h"
#include "zeroset/mesh/settings.h"
#include "zeroset/surface/field_survey.h"
#include "zeroset/surface/singular_set.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

/// What an improvement did: the remesher's or the paper improver's statistics, with the
/// options it ran with.
struct MeshImprovement {
  Improver improver = Improver::kRemesh;
  BoundaryMode boundary = BoundaryMode::kConstrained;
  RemeshOptions remesh_options;  ///< with improver kRemesh (singular_set: null)
  RemeshStats remesh;
  ImproveOptions paper_options;  ///< with improver kPaper
  ImproveStats paper;

  /// The figures both improvers have, as ImproveStats (steps: the remesher's iterations).
  ImproveStats summary() const;
  /// The "improve" object of a stats file: {"improver": "remesh"|"paper", ...}.
  nlohmann::json to_json() const;
};

struct MeshResult;

/// How mesh_surface() runs: what the front end wants besides the mesh, and where it listens.
struct MeshRun {
  int threads = 0;  ///< 0: as each stage chooses (ImproveOptions::threads, ...)
  /// The improver's step limit when the settings say "auto" (until at rest).
  int auto_steps = ImproveOptions{}.max_steps;
  bool survey = true;    ///< survey the field first (FieldSurvey and its warning)
  bool quality = false;  ///< measure quality and topology before and after improving
  /// Find the singular set also when the crossings step does not run (for a stats file or an
  /// overlay); the crossings step finds it whenever it runs.
  bool singular_set = false;
  /// The front end's name for MeshSettings::cells in a refusal ("--resolution", "cells").
  std::string cells_option = "cells";

  /// Each warning as it arises (kept in MeshResult::warnings too).
  std::function<void(const std::string&)> on_warning;
  /// Once the marching-cubes mesh has its crossings, before it is improved.
  std::function<void(const MeshResult&)> on_polygonized;
  /// The paper's improver after each step: `steps` so far, `done` after finish() (its last
  /// call). The remesher changes the connectivity as it goes and reports only its result.
  std::function<void(const MeshImprover&, int steps, bool done)> on_improver_step;
};

/// A mesh with everything that was measured on the way.
struct MeshResult {
  Surface surface;                    ///< as meshed
  MeshSettings settings;              ///< as validated
  Mesh mesh;                          ///< the singular curves left out when settings.curves is off
  std::optional<FieldSurvey> survey;  ///< with MeshRun::survey
  PolygonizeStats polygonize;
  std::size_t polygonized_vertices = 0;  ///< the marching-cubes mesh, before the crossings
  std::size_t polygonized_triangles = 0;
  std::optional<SingularSet> singular;  ///< found by the crossings step, or on request
  std::optional<CrossingStats> crossings;
  std::optional<MeshImprovement> improvement;  ///< when improving ran (a mesh, steps > 0)
  std::optional<MeshQuality> quality_before, quality_after;  ///< with MeshRun::quality
  std::optional<MeshTopology> topology_before, topology_after;
  std::vector<std::string> warnings;  ///< what the run found worth saying, in order
  double seconds = 0;                 ///< the whole run
  bool stopped = false;               ///< the stop token ended it early (the mesh is partial)

  /// The stats file of `zeroset mesh --stats` (docs/meshing.md, "Statistics").
  nlohmann::json to_json() const;
};

/// Meshes `surface` with `settings` (validated here: SettingError for a bad value). Throws
/// BadInput for a grid that would not fit in memory (named by run.cells_option). When `stop`
/// is requested the run returns early with `stopped` set.
MeshResult mesh_surface(const Surface& surface, const MeshSettings& settings,
                        const MeshRun& run = {}, std::stop_token stop = {});

/// The improvement stage of mesh_surface() alone, for a mesh made elsewhere (the viewer's
/// carried meshes): the remesher or the paper's improver as the settings say, `steps_done`
/// steps already counted against the step limit. `known`: the surface's singular set when the
/// caller has it (the remesher searches it otherwise). None when there is nothing to do (an
/// empty mesh, improvement off, the limit reached) or when `stop` ended it.
std::optional<MeshImprovement> improve_surface_mesh(Mesh& mesh, const Surface& surface,
                                                    const MeshSettings& settings,
                                                    const MeshRun& run = {},
                                                    const SingularSet* known = nullptr,
                                                    int steps_done = 0, std::stop_token stop = {});

}  // namespace zeroset
