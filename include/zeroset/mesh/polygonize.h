#pragma once
/// The polygonizer: marching cubes with a topologically consistent triangulation, vertices
/// refined onto F = 0 along their grid edges, triangles cut at the clip surface. How it works,
/// with every constant, is in docs/algorithms.md (section D) and docs/meshing.md.
///
/// What the result is:
///  - a consistently oriented, watertight 2-manifold away from the grid's edge and the clip;
///    triangles are counter-clockwise seen from the side ∇F points to;
///  - with `clip`, the vertices where triangles were cut at the clip surface G = 0 lie on the
///    curve F = 0 ∩ G = 0 and are flagged `is_boundary` (|G| ≤ 1e-12 there);
///  - where F is not finite (NaN or infinite: a logarithm of a negative number, a pole) there is
///    no surface: an edge with such an end holds no vertex, and a sign change across which |F|
///    does not get smaller (1/x − 1 at x = 0, a jump) is not a zero; the triangles on those
///    edges are left out, so the mesh ends there with an open border. Every vertex lies where F
///    is finite. Non-finite grid nodes are counted in PolygonizeStats::nan_samples;
///  - the sparse path (GridMode::kSparse, or kAuto on large grids) samples only bricks that a
///    first-order distance test keeps, and can miss surface parts that fit inside a brick
///    without reaching its corners or centre (tiny components, thin spikes): raise
///    `sparse_margin` or lower `brick_cells` when in doubt. Elsewhere it gives the dense path's
///    mesh.
#include <array>
#include <cstdint>
#include <optional>
#include <stop_token>
#include <string>

#include "zeroset/mesh/mesh.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

/// Dense grid, sparse bricks, or chosen by size.
enum class GridMode { kAuto, kDense, kSparse };

struct PolygonizeOptions {
  /// Region to polygonize; default: the bounding box of the surface's clip.
  std::optional<Box3> bounds;
  /// Cells along the longest side of the box (cells are cubes). Must be in [1, 32768].
  int cells = 128;
  /// kAuto picks the sparse path above `sparse_auto_nodes` grid nodes.
  GridMode mode = GridMode::kAuto;
  long long sparse_auto_nodes = 300LL * 300 * 300;
  /// Cells per side of a sparse brick.
  int brick_cells = 8;
  /// Safety factor of the sparse brick test (docs/algorithms.md D.7).
  double sparse_margin = 2.0;
  /// Refinement steps at most per edge vertex, one evaluation of F each (0: linear
  /// interpolation only).
  int refine_steps = 12;
  /// Sample expandable polynomial fields (Field::is_expandable()) row by row through their
  /// univariate restriction; other fields through the compiled expression.
  bool polynomial_rows = true;
  /// Cut triangles at the clip surface and flag the vertices there.
  bool clip = true;
  /// Mesh vertices closer than this many cells to the clip surface are moved onto it.
  double clip_snap_fraction = 0.1;
  /// Edges shorter than this many cells are collapsed (degenerate triangles).
  double collapse_fraction = 0.01;
  /// Fill `Mesh::normals` with ∇F/|∇F|.
  bool compute_normals = true;
  /// Worker threads; 0: all cores.
  int threads = 0;
};

/// What one polygonization did and how long it took.
struct PolygonizeStats {
  Box3 grid_bounds;                   ///< the box the grid covers
  std::array<int, 3> cells{0, 0, 0};  ///< cells per axis
  double cell_size = 0;
  bool sparse = false;
  long long bricks = 0;               ///< sparse path: bricks in the grid
  long long bricks_kept = 0;          ///< sparse path: bricks sampled
  long long grid_samples = 0;         ///< field values at grid nodes
  long long refine_evaluations = 0;   ///< field values spent refining edge vertices
  long long nan_samples = 0;          ///< grid nodes where F was not finite (NaN or ±∞)
  long long undefined_edges = 0;      ///< crossing edges with a non-finite end: no vertex
  long long pole_edges = 0;           ///< sign changes refused as poles or jumps: no vertex
  long long undefined_triangles = 0;  ///< triangles left out for a corner on such an edge
  long long active_cells = 0;         ///< cells the surface passes through
  long long ambiguous_faces = 0;      ///< face decisions made by the asymptotic decider
  long long edge_vertices = 0;        ///< vertices before clean-up and clipping
  long long welded_vertices = 0;      ///< vertices merged into one on a grid node where F = 0
  long long collapsed_edges = 0;      ///< degenerate triangles removed by edge collapse
  long long clip_cut_edges = 0;       ///< new vertices where mesh edges cross the clip
  long long clip_snapped = 0;         ///< vertices moved onto the clip curve
  double seconds_sampling = 0;        ///< field at the grid nodes
  double seconds_extraction = 0;      ///< classification, vertices (with refinement), triangles
  double seconds_refinement = 0;      ///< the refinement part of the extraction
  double seconds_cleanup = 0;         ///< collapses, clipping, normals
  double seconds_total = 0;
};

/// Polygonizes the surface inside its clip. Deterministic for given options (whatever the
/// thread count). Throws InvalidArgument for `cells` outside [1, 32768] or a bad option,
/// BadInput when the surface has no bounded clip and no `bounds` are given, and Error when the
/// mesh would exceed 2³² vertices. Returns an empty mesh as soon as `stop` is requested.
/// Thread safety: reentrant; uses its own evaluators.
Mesh polygonize(const Surface& surface, const PolygonizeOptions& options = {},
                PolygonizeStats* stats = nullptr, std::stop_token stop = {});

/// The grid the options give for this surface: box, cells per axis and cell size, and an
/// estimate of the peak memory of `polygonize` in bytes (the mesh, for a surface of area about
/// 6 × the box's cross-section, and dense: per worker F on three node layers and a slab's bit
/// sets; sparse: the bricks' corners). Cheap; throws like polygonize.
struct GridPlan {
  Box3 box;
  std::array<long long, 3> cells{0, 0, 0};
  double cell_size = 0;
  bool sparse = false;
  double estimated_bytes = 0;
};
GridPlan plan_grid(const Surface& surface, const PolygonizeOptions& options = {});

/// Refuses options whose grid (plan_grid's estimate) would not fit in the memory this process
/// may still take (available_memory in zeroset/io/memory.h: RAM, ulimit -v, the cgroup's
/// limit): throws InvalidArgument naming `option` (what the front end calls the resolution),
/// the limit that applies and the largest resolution that fits. For front ends, before a
/// long run; polygonize itself does not call it.
void check_grid_memory(const Surface& surface, PolygonizeOptions options,
                       const std::string& option);

}  // namespace zeroset
