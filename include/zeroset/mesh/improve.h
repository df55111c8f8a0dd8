#pragma once
/// The mesh improver (Rösch, Ruhl & Saupe 1997, §4): the mesh is a spring–mass system whose
/// massless vertices are held on F = 0 by the floaters' constrained velocity. Springs are
/// stiffer where the normals turn and near singular points, so vertices gather at creases and
/// nodes while the triangles relax towards regular ones. The formulas and constants are in
/// docs/algorithms.md (section C); docs/meshing.md shows what it does to a mesh.
///
/// One step: F and ∇F at every vertex; the spring forces, made tangent to F = 0 (and to the
/// clip surface for boundary vertices, BoundaryMode::kConstrained); moves bounded by the
/// vertex's shortest edge and shortened or cancelled wherever a triangle would turn over,
/// fold or collapse; during the first `flip_steps` steps Delaunay edge flips between nearly
/// coplanar triangles; and singular points found from the field alone (Newton's method on
/// ∇F = 0), each then held by its nearest vertex. The improver stops when every vertex moves
/// less than `speed_threshold` mean edge lengths in a step; finish() then projects every free
/// vertex onto F = 0. No move takes a vertex out of the clip or onto a point where F or ∇F is
/// not finite (a pole, a NaN region): such moves are refused and the vertex stays.
#include <cstdint>
#include <memory>
#include <stop_token>
#include <vector>

#include "zeroset/mesh/mesh.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

enum class BoundaryMode {
  kFixed,        ///< boundary vertices do not move
  kConstrained,  ///< they slide along the clip curve F = 0 ∩ G = 0 (paper §4.2)
};

struct ImproveOptions {
  int max_steps = 300;      ///< improve_mesh stops after this many steps
  double relaxation = 0.5;  ///< λ: fraction of the way to the spring equilibrium per step
  /// β: share of its last tangential move a vertex carries into the next, on flat parts more
  /// than three rings from singular curves (heavy-ball momentum; 0: none)
  double inertia = 0.9;
  double feedback = 1.0;            ///< φ·dt: fraction of the Newton correction to F = 0 per step
  double spring_base = 1.0;         ///< κ_0
  bool use_curvature = true;        ///< add the curvature estimator (paper eq. 6)
  double curvature_weight = 8.0;    ///< κ_d
  bool use_singularity = true;      ///< add the singularity estimator β (docs/algorithms.md B.3)
  double singularity_weight = 4.0;  ///< κ_s
  double singularity_scale = 3.0;   ///< γ_s in mean edge lengths
  int singularity_interval = 5;     ///< steps between Hessian evaluations for β
  bool find_singular_points = true;   ///< Newton on ∇F = 0; moves and holds the nearest vertex
  bool flip_edges = true;             ///< Delaunay edge flips between nearly coplanar triangles
  double flip_max_dihedral_deg = 25;  ///< flip only where the two triangles bend less than this
  int flip_steps = 40;  ///< flip during the first steps only, then let the springs settle
  BoundaryMode boundary = BoundaryMode::kConstrained;
  double speed_threshold = 5e-3;   ///< converged when every move < this × mean edge length
  double max_move_fraction = 0.3;  ///< a move is at most this × the vertex's shortest edge
  double min_area_fraction = 1e-3;  ///< a triangle must keep ≥ this × mean edge length² × √3/4
  bool final_projection = true;     ///< improve_mesh calls finish() at the end
  int threads = 0;                  ///< 0: one per 100 000 vertices, at most all cores
};

/// Figures of the last step (or of the whole run in improve_mesh).
struct ImproveStats {
  int steps = 0;
  bool converged = false;
  double max_move = 0;  ///< largest move of the last step, in mean edge lengths
  double mean_edge_length = 0;
  long long flips = 0;            ///< edge flips so far
  long long shortened_moves = 0;  ///< moves halved by the flip guard so far
  long long cancelled_moves = 0;  ///< moves cancelled by the flip guard so far
  long long flipped_triangles =
      0;  ///< triangles facing against ∇F now (should stay 0 on smooth parts)
  std::vector<Vec3> singular_points;  ///< points found with F ≈ 0 and ∇F ≈ 0, each held by a vertex
  /// Moves refused so far, the vertex staying where it was: out of the clip, or onto a point
  /// where F or ∇F is not finite (found at the next evaluation and undone).
  long long refused_moves = 0;
  /// After finish(): vertices where F is not finite. Each is a failure: max_residual is then
  /// the largest double.
  long long undefined_vertices = 0;
  double max_residual = 0;  ///< max |F|/|∇F| over free vertices after finish()
  double seconds = 0;
};

/// A stateful improver for step-by-step use (the viewer steps it and draws `mesh()`).
/// Not thread-safe; one step uses `threads` workers internally.
class MeshImprover {
 public:
  /// Takes the mesh (from `polygonize`; `is_boundary` may be empty: no boundary). Throws
  /// InvalidArgument for bad options or a mesh whose triangles refer to missing vertices.
  MeshImprover(Mesh mesh, const Surface& surface, const ImproveOptions& options = {});
  ~MeshImprover();
  MeshImprover(MeshImprover&&) noexcept;
  MeshImprover& operator=(MeshImprover&&) noexcept;

  /// One step (see the header comment). Returns the running statistics.
  const ImproveStats& step();
  /// Every vertex moved less than the threshold in the last step.
  bool converged() const;
  /// Projects the free vertices onto F = 0 (boundary vertices onto the clip curve) with the
  /// flip guard and refreshes the normals. Idempotent.
  void finish();

  const Mesh& mesh() const;
  const ImproveStats& stats() const;
  /// Moves the mesh out; the improver is empty afterwards.
  Mesh take_mesh();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Improves `mesh` in place: steps until converged, `max_steps` or `stop`, then finish()
/// (when `final_projection`). Returns the statistics.
ImproveStats improve_mesh(Mesh& mesh, const Surface& surface, const ImproveOptions& options = {},
                          std::stop_token stop = {});

}  // namespace zeroset
