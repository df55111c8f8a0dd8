#pragma once
// What the parts of the polygonizer share: the grid, the crossing edges and their linear
// points, the choice of a cell's table entry, and the two extraction paths (dense slabs,
// sparse bricks) that polygonize() picks from.
#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stop_token>
#include <vector>

#include "cell_triangulation_detail.h"
#include "mc_table_detail.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/mesh/polygonize.h"

namespace zeroset::detail {

using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Vertex ids are 32 bits; a few values at the top stay free.
inline constexpr std::uint64_t kMaxVertices = 0xfffffff0ull;

// Cell layers per slab of the dense path at most (fewer on small grids, see slab_layers).
inline constexpr long long kSlabLayers = 16;

// A grid of cubic cells; node (i, j, k) is at lo + h·(i, j, k).
struct Grid {
  Vec3 lo = Vec3::Zero();
  double h = 1;
  std::array<long long, 3> cells{0, 0, 0};
  long long nx() const { return cells[0] + 1; }
  long long ny() const { return cells[1] + 1; }
  long long nz() const { return cells[2] + 1; }
  double coord(int axis, long long i) const { return lo[axis] + static_cast<double>(i) * h; }
  Vec3 node(long long i, long long j, long long k) const {
    return {coord(0, i), coord(1, j), coord(2, k)};
  }
};

// The grid of the options' box (or the surface's bounds) after checking the options.
Grid make_grid(const Surface& surface, const PolygonizeOptions& o);
// Whether the mesh is cut at the surface's clip.
bool clips(const Surface& s, const PolygonizeOptions& o);
// Whether the grid is worked through sparse bricks rather than dense slabs.
bool use_sparse(const Grid& g, const PolygonizeOptions& o);

// One crossing edge: its lower node, axis and the field values at both ends.
struct Crossing {
  long long i, j, k;
  int axis;
  double fa, fb;
};

// The position of a crossing that is not a zero of F: an edge with an end where F is not finite
// (NaN or infinite is "no surface", not a sign), or a sign change across a pole or a jump,
// where F does not get smaller towards the change. polygonize() drops the triangles on it.
inline Vec3 no_vertex() { return Vec3::Constant(std::numeric_limits<double>::quiet_NaN()); }

// Whether both end values of an edge are finite: only such an edge can hold a vertex.
inline bool finite_ends(double fa, double fb) { return std::isfinite(fa) && std::isfinite(fb); }

// Whether refinement on an edge with finite end values fa, fb of opposite signs clearly found a
// zero of F: the smallest |F| met is 0 or well below both ends' (near a simple root it drops by
// orders of magnitude; a pole or a jump makes |F| grow or stay towards the sign change). The
// other cases (a pole; a jump; a zero within rounding of an end) are told apart by the
// first-order distance |F|/|∇F| at the vertex (VertexPlacer::place_batched).
inline bool clearly_refined(double fa, double fb, double smallest) {
  return smallest == 0 || smallest < 0.5 * std::min(std::abs(fa), std::abs(fb));
}
// The largest |F|/|∇F| at a vertex, in cells, that an unclear refinement may leave (a zero
// within rounding of an end has |F|/|∇F| at rounding level; a pole next to a node, one cell).
inline constexpr double kMaxVertexResidual = 1e-6;

// Where the sign changes on the edge by linear interpolation, as a fraction of the edge.
inline double linear_fraction(double fa, double fb) {
  const double s = fa / (fa - fb);
  return std::isfinite(s) ? std::clamp(s, 0.0, 1.0) : 0.5;
}

// The linear interpolation of the crossing on the edge from node (i, j, k) along `axis`. The
// triangulation of each cube uses these points (not the refined ones) so that the dense and
// the sparse path, which refines later, triangulate alike.
inline Vec3 linear_point(const Grid& g, long long i, long long j, long long k, int axis, double fa,
                         double fb) {
  Vec3 p = g.node(i, j, k);
  p[axis] += linear_fraction(fa, fb) * g.h;
  return p;
}

// The table entry of a cell of the given case: its ambiguous faces are decided by the
// asymptotic decider on `corner(c)`, the value at corner c (Lorensen numbering), read only
// for those faces. Counts the decisions in `ambiguous`.
template <class Corner>
const CellPolygons& cell_entry(const CellPolygons* table, int cube_case, Corner&& corner,
                               long long& ambiguous) {
  const int amb = kAmbiguousFaces[static_cast<size_t>(cube_case)];
  int rank = 0;
  if (amb) {  // rare
    int t = 0;
    for (int f = 0; f < 6; ++f) {
      if (!((amb >> f) & 1)) continue;
      const auto& q = kFaceCanonical[f];
      if (positive_corners_connected(corner(q[0]), corner(q[1]), corner(q[2]), corner(q[3])))
        rank |= 1 << t;
      ++t;
    }
    ambiguous += std::popcount(static_cast<unsigned>(amb));
  }
  return table[kCaseFirst[static_cast<size_t>(cube_case)] + static_cast<size_t>(rank)];
}

using Triangle = std::array<std::uint32_t, 3>;

// The vertices (one per crossing edge, refined) and triangles that a path extracts, before
// the clean-up.
struct ExtractedMesh {
  std::vector<Vec3> positions;
  std::vector<Triangle> triangles;
};

// The dense path: every node sampled, slab by slab (dense_slabs.cpp). `poly`: F expanded,
// or null to evaluate the field. Adds to the statistics; returns nothing once `stop` is set.
ExtractedMesh extract_dense(const Surface& surface, const Grid& g, const PolygonizeOptions& o,
                            const Polynomial* poly, int workers, PolygonizeStats& st,
                            const std::stop_token& stop);
// The sparse path: only the bricks near the surface sampled (sparse_bricks.cpp); vertices
// numbered by their edges in the dense path's order.
ExtractedMesh extract_sparse(const Surface& surface, const Grid& g, const PolygonizeOptions& o,
                             const Polynomial* poly, int workers, PolygonizeStats& st,
                             const std::stop_token& stop);

}  // namespace zeroset::detail
