#pragma once
/// The polygonizer (DESIGN §4, ALGORITHMS §D): marching cubes with a topologically consistent
/// triangulation, vertices on F = 0, triangles cut at the clip surface.
///
/// How it works:
///  - The grid has cubic cells; `cells` of them span the longest side of the box. F is sampled
///    at every node, a row at a time: for polynomials the row's restriction to a line is a
///    univariate polynomial evaluated by Horner's rule, otherwise the field is evaluated over
///    structure-of-arrays rows (Evaluator::values). F ≥ 0 (and NaN) counts as positive. The
///    dense path works through slabs of 16 cell layers, one per worker at a time from sampling
///    to triangles a node layer at a time, so a worker holds F on three node layers and the
///    bit sets of one slab rather than the whole grid (the two node layers above a slab are
///    sampled again by the next one).
///  - Every sign-changing grid edge gets exactly one vertex, numbered by the edge (a per-row
///    prefix count over bit sets, as in Flying Edges, Schroeder et al. 2015), so neighbouring
///    cells share it without welding by coordinates. The vertex starts at the linear
///    interpolation and is refined on the edge, in batches over all edges: for polynomials by
///    Newton's method on the edge's univariate restriction, kept inside a bracket whose
///    Illinois estimate (regula falsi) takes over where Newton's steps stop shrinking fast, as
///    where the surface touches the edge; for other fields by the Illinois method.
///  - Each cube's surface is built from the segments on its six faces: a face with four sign
///    changes is resolved by the asymptotic decider (Nielson & Hamann 1991), computed from the
///    face's own values in one canonical order, so both cubes that share a face connect the
///    same points. The segments close into oriented cycles (positive side on the left, seen
///    from outside the cube), every cycle is a disc, triangulated to maximise the smallest
///    triangle quality, never with a diagonal between two points of one cube face. The
///    result is a consistently oriented, watertight 2-manifold away from the grid's edge;
///    triangles are counter-clockwise seen from the side ∇F points to.
///  - Degenerate triangles (an edge shorter than `collapse_fraction` cells) are removed by
///    edge collapses that keep the mesh watertight (see collapse_short_edges).
///  - With `clip`, triangles are cut where the clip function G changes sign. A new vertex is
///    put where the mesh edge meets G = 0 and then moved onto the curve F = 0 ∩ G = 0 by
///    Newton's method on both constraints (minimum-norm steps); a vertex already within
///    `clip_snap_fraction` cells of the clip surface is moved onto that curve instead of
///    cutting next to it. Those vertices are flagged `is_boundary`; they satisfy |G| ≤ 1e-12
///    (G is exactly zero up to rounding after the final projection onto the clip part).
///    A triangle with all three vertices on the clip is kept only where F = 0 runs along the
///    clip there (∇F and ∇G within 26° of parallel); elsewhere it is a sliver in the clip
///    surface (a grid face in a box clip's plane), often facing against ∇F, and is dropped.
///  - The sparse path samples the grid in bricks of `brick_cells`³ cells and only where the
///    surface may be. A brick is kept when the signs of F at its 8 corners and its centre
///    differ, or when min |F| over those 9 points ≤ `sparse_margin` · |∇F(centre)| · (brick
///    half diagonal), a first-order distance test. It can miss surface parts that fit inside
///    a brick without reaching its corners or centre where F varies much faster than its
///    central gradient predicts (tiny components, thin spikes); raise `sparse_margin` or
///    lower `brick_cells` when in doubt. Both paths number vertices and triangulate cubes
///    alike, so they give the same mesh wherever the sparse one keeps every brick that meets
///    the surface.
#include <array>
#include <cstdint>
#include <optional>
#include <stop_token>

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
  /// Safety factor of the sparse brick test (see the header comment).
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
  Box3 grid_bounds;                    ///< the box the grid covers
  std::array<int, 3> cells{0, 0, 0};   ///< cells per axis
  double cell_size = 0;
  bool sparse = false;
  long long bricks = 0;                ///< sparse path: bricks in the grid
  long long bricks_kept = 0;           ///< sparse path: bricks sampled
  long long grid_samples = 0;          ///< field values at grid nodes
  long long refine_evaluations = 0;    ///< field values spent refining edge vertices
  long long nan_samples = 0;           ///< grid nodes where F was not finite (counted positive)
  long long active_cells = 0;          ///< cells the surface passes through
  long long ambiguous_faces = 0;       ///< face decisions made by the asymptotic decider
  long long edge_vertices = 0;         ///< vertices before clean-up and clipping
  long long collapsed_edges = 0;       ///< degenerate triangles removed by edge collapse
  long long clip_cut_edges = 0;        ///< new vertices where mesh edges cross the clip
  long long clip_snapped = 0;          ///< vertices moved onto the clip curve
  double seconds_sampling = 0;         ///< field at the grid nodes
  double seconds_extraction = 0;       ///< classification, vertices (with refinement), triangles
  double seconds_refinement = 0;       ///< the refinement part of the extraction
  double seconds_cleanup = 0;          ///< collapses, clipping, normals
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

}  // namespace zeroset
