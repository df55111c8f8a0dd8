#pragma once
// The crossings step's pieces shared by its two files: the network of singular curves, the
// tube cut out around the crossing curves, and the join of the cut's rim to the curves
// (crossings_rim.cpp). See docs/meshing.md ("Crossings").
#include <array>
#include <cstdint>
#include <string>
#include <unordered_set>
#include <vector>

#include "mesh_detail.h"
#include "zeroset/mesh/mesh.h"
#include "zeroset/surface/singular_index.h"
#include "zeroset/surface/singular_set.h"
#include "zeroset/surface/surface.h"

namespace zeroset::detail {

// A rim that turns back this many tube radii or less before a curve's free end (a pinch
// point) is joined to the end: towards a pinch point the sheets close like a book, and the
// grid loses them a few cells before it.
inline constexpr double kFreeEndReach = 4.0;

// The singular curves as a graph whose vertices become mesh vertices. Only the crossing
// curves' edges are in `adj` (the strips are joined to them); isolated curves share vertices
// with them at pinch points.
struct Network {
  struct Curve {
    CurveKind kind = CurveKind::kCrossing;
    std::vector<std::uint32_t> verts;
    std::vector<double> arc;  // arc length at each vertex
    bool closed = false;
    double length() const { return arc.empty() ? 0.0 : arc.back(); }
  };
  std::vector<Vec3> pos;
  std::vector<std::vector<std::uint32_t>> adj;
  std::vector<std::uint8_t> special;   // curve end, junction, pinch or triple point
  std::vector<std::uint8_t> free_end;  // the end of one crossing curve, inside the clip
  std::vector<std::uint8_t> clip_end;  // the end of one crossing curve, on the clip
  std::vector<Curve> curves;

  // Points closer than `merge` are one vertex (curves share their triple and pinch points).
  std::uint32_t vertex_at(const Vec3& p, double merge) {
    for (std::uint32_t v = 0; v < pos.size(); ++v)
      if ((pos[v] - p).norm() <= merge) return v;
    pos.push_back(p);
    adj.emplace_back();
    return static_cast<std::uint32_t>(pos.size() - 1);
  }
};

// The crossing curves of the network alone, for nearest-segment queries, and the network
// curve each one is.
struct CrossingCurves {
  SingularSet set;
  std::vector<std::uint32_t> curve_of;
};

// The mesh with the tube around the crossing curves cut out: the triangles kept and the
// half-edges of those removed.
struct TubeCut {
  std::vector<std::array<std::uint32_t, 3>> kept;
  std::vector<std::array<std::uint32_t, 3>> removed;
  std::unordered_set<std::uint64_t> removed_edges;
};

// Where and why a chain of the cut's rim could not be joined to the curves.
struct JoinFailure {
  Vec3 where = Vec3::Zero();
  std::string what;
};

// Joins the rim of the cut to the crossing curves: each rim edge u → v and the graph path
// between the vertices its ends are joined to bound a polygon (v, u, a_0 … a_k), fanned from u
// over the path's first part and from v over the rest: triangles run like the kept triangle's,
// so each half-sheet keeps its side. Returns the triangles (vertex base + i is graph vertex i);
// the chains that cannot be joined add nothing and are listed in `failures`.
std::vector<std::array<std::uint32_t, 3>> join_rim(const Mesh& mesh, const Surface& surface,
                                                   const TubeCut& cut, const Network& net,
                                                   const SingularSetIndex& index,
                                                   const CrossingCurves& crossing, double reach,
                                                   std::vector<JoinFailure>& failures);

}  // namespace zeroset::detail
