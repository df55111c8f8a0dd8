#pragma once
/// Carrying a mesh along a change of the surface's parameters (docs/meshing.md, "Carrying a
/// mesh"): instead of polygonizing and improving again, every vertex is moved onto the new
/// surface and the improver takes a few steps. The viewer's mesh mode follows a moving
/// parameter this way, and rebuilds from scratch only when carrying fails.
///
/// Each free vertex moves by the floaters' parameter term dx = −(F_q·Δq) ∇F/|∇F|² (evaluated on
/// the old surface, docs/algorithms.md A.4) and is then Newton-projected onto the new F = 0;
/// vertices near a node are moved with the node instead (∇F vanishes there), node vertices go
/// to the new node exactly, boundary vertices onto the new curve F = 0 ∩ G = 0, vertices of a
/// singular curve back onto ∇F = 0. Carrying fails, and says why, where the mesh cannot follow:
/// the equation or the number of singular points or curves changed, a vertex's projection fails
/// or corrects the first-order prediction by more than a fraction of an edge, the clip now cuts
/// the mesh elsewhere, or the result is worse than a rebuild (triangles facing against ∇F away
/// from the singular set, a collapsed angle, a residual left).
#include <cstdint>
#include <optional>
#include <stop_token>
#include <string>
#include <string_view>
#include <vector>

#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/mesh.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

/// The singular set as carrying compares it: the singular points, and how many singular curves
/// there are (−1: a sheet of singular points, never carried).
struct CarrySingularSet {
  std::vector<Vec3> points;
  int curves = 0;
};

struct CarryOptions {
  /// Improver steps after the move (then MeshImprover::finish()); 0: projection only.
  int improve_steps = 3;
  /// The improver's options for those steps (max_steps and final_projection are ignored).
  ImproveOptions improve;
  /// Newton's projection may correct a vertex's predicted position by at most this × the mean
  /// length of its edges.
  double max_move_edges = 0.5;
  /// Most |F|/|∇F| left at a vertex away from the singular set, × the mean edge length.
  double max_residual_edges = 1e-6;
  /// The smallest angle away from the singular set may not fall below this (degrees) unless
  /// it was already that small before.
  double min_angle_deg = 1;
  /// Seed cells of find_singular_set() for surfaces without known singular points (0: the
  /// singular set is not searched; only known points are compared).
  int singular_cells = 24;
  int threads = 0;  ///< 0: one per 100 000 vertices, at most all cores (as the improver)
  /// The singular set of `from` when the caller has it: CarryResult::singular of the carry that
  /// led to `from` (same singular_cells). Carrying step after step then searches each surface
  /// once instead of twice. Unset: searched. Ignored for surfaces with known singular points.
  std::optional<CarrySingularSet> from_singular;
};

/// Why carrying failed.
enum class CarryFailure : std::uint8_t {
  kNone,         ///< carried
  kEquation,     ///< the field is another one (a different equation)
  kSingularSet,  ///< singular points or curves appeared or disappeared
  kProjection,   ///< a vertex found no point of the new surface nearby
  kLongMove,     ///< Newton corrected a vertex by more than max_move_edges of its edges
  kClip,         ///< the clip cuts the mesh elsewhere (a vertex left it, the curve moved off)
  kFlipped,      ///< triangles face against ∇F away from the singular set
  kAngle,        ///< the smallest angle collapsed
  kResidual,     ///< vertices were left off F = 0
  kStopped,      ///< the stop token was requested
};
std::string_view to_string(CarryFailure failure);

struct CarryResult {
  CarryFailure failure = CarryFailure::kNone;
  std::string
      reason;  ///< what failed, in words, e.g. "singular points: 4 → 16"; empty when carried
  Mesh mesh;   ///< the carried mesh (normals ∇F/|∇F|); empty when carrying failed
  double max_move_edges = 0;      ///< largest vertex move, in the vertex's mean edge lengths
  double max_residual = 0;        ///< max |F|/|∇F| away from the singular set, after
  double smallest_angle_deg = 0;  ///< smallest angle away from the singular set, after
  long long flipped_triangles = 0;
  int node_vertices = 0;  ///< vertices put onto the new singular points
  ImproveStats improve;   ///< of the improver steps
  /// The singular set of `to` (once it was compared, also when carrying failed afterwards):
  /// CarryOptions::from_singular of the next carry from this result's mesh.
  std::optional<CarrySingularSet> singular;
  double seconds = 0;
  bool carried() const { return failure == CarryFailure::kNone; }
};

/// Carries `mesh`, which lies on `from`, onto `to`: the same equation with other parameter
/// values (and the clip at those values). Never throws for a mesh that cannot follow: the
/// result says why (see the header comment). Throws InvalidArgument for bad options and a mesh
/// whose triangles refer to missing vertices. Cost: a sample with parameter derivatives and a
/// few Newton steps per vertex, the improver steps, and one evaluation per triangle for the
/// checks (milliseconds for 10⁴ vertices).
CarryResult carry_mesh(const Mesh& mesh, const Surface& from, const Surface& to,
                       const CarryOptions& options = {}, std::stop_token stop = {});

}  // namespace zeroset
