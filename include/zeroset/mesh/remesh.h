#pragma once
/// Isotropic remeshing of a zeroset mesh (docs/meshing.md, "The remesher"): iterations of
/// edge splits (edges longer than 4/3 L, the new vertex put onto F = 0 by Newton's method with
/// the exact gradient), edge collapses (shorter than 4/5 L, refused when a triangle would turn
/// over, an edge longer than 4/3 L would appear, or the link condition fails), edge flips
/// towards valence 6 (4 on the border), and tangential relaxation (area-weighted centroids in the
/// tangent plane) followed by Newton projection onto F = 0. After the last iteration a few
/// rounds of Delaunay flips between nearly coplanar triangles and relaxation polish the angles.
///
/// Features are locked: vertices on isolated singular points (found by find_singular_set when
/// the clip is bounded, the nearest vertex moved exactly onto each), the vertices and edges of
/// Mesh::curves (a crossing curve's edges keep their four triangles), vertices on an open
/// border that is not the clip. Vertices on the clip curve F = 0 ∩ G = 0 slide along it
/// (BoundaryMode::kConstrained) or stay (kFixed); border edges are split and collapsed along
/// the curve, new vertices put back onto it. No operation leaves a triangle of (near) zero area
/// or one turned against its former orientation: each is checked before it is applied.
///
/// Next to pinch points (found with the singular set) the two sheets close like a book and
/// marching cubes bridges them: there, within 9 L of each pinch point, the spring–mass
/// improver (improve_mesh) relaxes the mesh first, its curvature springs pulling vertices into
/// the fold, and the remesher then holds the vertices within 6 L as it left them, projecting
/// them onto F = 0 at the end (docs/meshing.md, "Crossings").
#include <stop_token>
#include <vector>

#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/mesh.h"
#include "zeroset/surface/singular_set.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

struct RemeshOptions {
  double target_edge = 0;   ///< L; 0: the mean edge length of the input mesh
  int max_iterations = 30;  ///< split/collapse/flip/relax rounds at most
  int relax_steps = 3;      ///< relaxation steps per iteration
  /// Delaunay flip + relaxation rounds after the iterations, at most (then up to 20 rounds of
  /// flips alone; 0: no polish).
  int polish_rounds = 10;
  BoundaryMode boundary = BoundaryMode::kConstrained;
  bool find_singular_points = true;  ///< lock a vertex on every isolated singular point
  /// At rest when no split, collapse or flip applies and every relaxation move is below this
  /// × L.
  double rest_move = 5e-3;
  /// 0: from 20 000 vertices on, relaxation runs on all cores or on one, whichever its steps
  /// measure faster (on a busy machine one is); a smaller mesh on one. The mesh is the same
  /// for any number of workers.
  int threads = 0;
  /// The surface's singular set when the caller has found it already (mesh_crossings() does),
  /// so that it is not found twice; null: remesh() finds it (with find_singular_points and a
  /// bounded clip). Must outlive the call.
  const SingularSet* singular_set = nullptr;
};

struct RemeshStats {
  int iterations = 0;
  bool converged = false;
  long long splits = 0;
  long long collapses = 0;
  long long flips = 0;  ///< valence and Delaunay flips
  long long refused_collapses = 0;
  long long relax_steps = 0;     ///< relaxation steps, over all iterations
  long long reverted_moves = 0;  ///< relaxation moves undone because a triangle would turn over
  double target_edge = 0;
  double last_max_move = 0;           ///< largest relaxation move of the last iteration, in L
  std::vector<Vec3> singular_points;  ///< points held exactly by a vertex
  /// Isolated singular points found that no vertex could take without turning a triangle
  /// over (0 on every surface tested).
  long long missed_singular_points = 0;
  /// Vertices next to pinch points placed by the spring–mass improver and then held (see the
  /// header comment), and its steps there. The steps are counted also when its result was put
  /// back (a flip there would have made an edge of three triangles): then no vertex is held.
  long long pinch_held_vertices = 0;
  int pinch_improver_steps = 0;
  double max_residual = 0;  ///< max |F|/|∇F| over the vertices that move (not the locked)
  long long undefined_vertices = 0;
  double seconds = 0;
};

/// Remeshes `mesh` in place (see the header comment). `mesh.is_boundary` may be empty; curves
/// are renumbered with the vertices. Throws InvalidArgument for bad options or a mesh whose
/// triangles refer to missing vertices.
RemeshStats remesh(Mesh& mesh, const Surface& surface, const RemeshOptions& options = {},
                   std::stop_token stop = {});

}  // namespace zeroset
