#pragma once
/// The mesh improver (Rösch, Ruhl & Saupe 1997, §4.1–4.3; ALGORITHMS §C): the mesh is a
/// spring–mass system whose massless vertices are held on F = 0 by the floaters' constrained
/// velocity.
///
/// The spring model. The paper's springs have rest length zero and constants
/// κ_ij = κ_d (1 − cos(n_i, n_j)) (eq. 6). Taken literally, springs on flat parts have κ = 0,
/// so flat parts never move and their triangles stay as the polygonizer made them. Here
///     κ_ij = κ_0 + κ_d (1 − cos(n_i, n_j)) + κ_s (1 − min(β_i, β_j)),
/// a base constant κ_0 (the paper's "default value"), the paper's curvature estimator, and the
/// singularity estimator β of the floaters (ALGORITHMS §B: β = min(‖r‖/γ_s, 1) with
/// F_xx r = F_x, the length of a Newton step towards ∇F = 0). Zero-rest-length springs make
/// each vertex's equilibrium the κ-weighted mean of its neighbours, so
///     P_i = λ (Σ_j κ_ij p_j / Σ_j κ_ij − p_i)
/// is the paper's desired velocity P_i = −2 Σ_j κ_ij r_ij with a per-vertex time step
/// dt_i = λ / (2 Σ_j κ_ij): a tangential Laplacian smoothing step that relaxes to regular
/// triangles, while stiffer springs where normals turn (creases, the cone of a node) or
/// near singular points pull vertices there, which irons out the notches marching cubes
/// leaves at nodes (paper figures 8, 9).
///
/// One step:
///  1. F and ∇F at every vertex (batched); every `singularity_interval` steps also the
///     Hessian for β.
///  2. P_i from the springs; the constrained velocity (paper eq. 1–2, as for floaters)
///     ṗ_i = P_i − [(F_x·P_i + φF)/(F_x·F_x + ε²)] F_x, with ε = 1e-3 × the median |∇F| so
///     that nothing divides by zero at singular points (the pull towards F = 0 weakens there
///     but never points the wrong way). φ = `feedback` per step (1: a full Newton step).
///  3. Boundary vertices are either fixed, or constrained to the clip curve F = 0 ∩ G = 0
///     by the second constraint G_x·ṗ + φG = 0 of §4.2: the velocity is projected onto the
///     curve's tangent (both constraints solved together, regularised where ∇F ∥ ∇G), and the
///     vertex is put back exactly on G = 0 after the move.
///  4. No step may turn a triangle over: moves are bounded by `max_move_fraction` of the
///     vertex's shortest edge, then every triangle that would turn over relative to ∇F (its
///     normal against the sum of its vertices' unit gradients, where it agreed before), fold
///     by more than 90° against its old normal, or lose nearly all of its area has the moves
///     of its vertices halved, up to 6 times, then cancelled.
///  5. Optional complements: Delaunay edge flips between nearly coplanar triangles during the
///     first `flip_steps` steps (the paper moves vertices only; flips fix the vertex valences
///     marching cubes leaves, which vertex motion alone cannot, and never bend the surface by
///     more than `flip_max_dihedral_deg`; a flip must beat the Delaunay test by 0.05 rad so
///     that edges do not flip back and forth while vertices move),
///     and singular points found from the field alone: from vertices whose Newton step to
///     ∇F = 0 is shorter than an edge, Newton's method on ∇F = 0 finds points with F ≈ 0 and
///     ∇F ≈ 0 (no list of known singular points is used); the nearest vertex is moved there
///     (with the flip guard) and then held.
/// The improver stops when every vertex moves less than `speed_threshold` mean edge lengths
/// in a step. Then `finish()` projects every free vertex onto F = 0 by guarded Newton steps
/// (boundary vertices onto the clip curve).
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
  int max_steps = 300;               ///< improve_mesh stops after this many steps
  double relaxation = 0.5;           ///< λ: fraction of the way to the spring equilibrium per step
  double feedback = 1.0;             ///< φ·dt: fraction of the Newton correction to F = 0 per step
  double spring_base = 1.0;          ///< κ_0
  bool use_curvature = true;         ///< add the curvature estimator (paper eq. 6)
  double curvature_weight = 8.0;     ///< κ_d
  bool use_singularity = true;       ///< add the singularity estimator β (ALGORITHMS §B)
  double singularity_weight = 4.0;   ///< κ_s
  double singularity_scale = 3.0;    ///< γ_s in mean edge lengths
  int singularity_interval = 5;      ///< steps between Hessian evaluations for β
  bool find_singular_points = true;  ///< Newton on ∇F = 0; moves and holds the nearest vertex
  bool flip_edges = true;            ///< Delaunay edge flips between nearly coplanar triangles
  double flip_max_dihedral_deg = 25; ///< flip only where the two triangles bend less than this
  int flip_steps = 40;               ///< flip during the first steps only, then let the springs settle
  BoundaryMode boundary = BoundaryMode::kConstrained;
  double speed_threshold = 5e-3;     ///< converged when every move < this × mean edge length
  double max_move_fraction = 0.3;    ///< a move is at most this × the vertex's shortest edge
  double min_area_fraction = 1e-3;   ///< a triangle must keep ≥ this × mean edge length² × √3/4
  bool final_projection = true;      ///< improve_mesh calls finish() at the end
  int threads = 0;                   ///< 0: one per 100 000 vertices, at most all cores
};

/// Figures of the last step (or of the whole run in improve_mesh).
struct ImproveStats {
  int steps = 0;
  bool converged = false;
  double max_move = 0;             ///< largest move of the last step, in mean edge lengths
  double mean_edge_length = 0;
  long long flips = 0;             ///< edge flips so far
  long long shortened_moves = 0;   ///< moves halved by the flip guard so far
  long long cancelled_moves = 0;   ///< moves cancelled by the flip guard so far
  long long flipped_triangles = 0; ///< triangles facing against ∇F now (should stay 0 on smooth parts)
  std::vector<Vec3> singular_points;  ///< points found with F ≈ 0 and ∇F ≈ 0, each held by a vertex
  double max_residual = 0;         ///< max |F|/|∇F| over free vertices after finish()
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
