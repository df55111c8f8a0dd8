#pragma once
// Pieces shared by the polygonizer and the improver.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "zeroset/expr/field.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/mesh.h"
#include "zeroset/surface/surface.h"

namespace zeroset::detail {

// No vertex, triangle or curve: the index the mesh code stores where there is none.
inline constexpr std::uint32_t kNone = 0xffffffffu;

// A half-edge a → b as one integer (a in the high word), for hash sets and maps.
inline std::uint64_t directed_edge_key(std::uint32_t a, std::uint32_t b) {
  return (static_cast<std::uint64_t>(a) << 32) | b;
}

// An undirected edge {a, b} as one integer: the half-edge from the smaller index.
inline std::uint64_t edge_key(std::uint32_t a, std::uint32_t b) {
  return a < b ? directed_edge_key(a, b) : directed_edge_key(b, a);
}

struct ClipCutStats {
  long long cut_edges = 0;  // new vertices where an edge crosses G = 0
  long long snapped = 0;    // vertices moved onto the clip curve instead
};

// Cuts the mesh at the clip surface G = 0 (see polygonize.h): keeps what is inside, puts new
// vertices on F = 0 ∩ G = 0, moves vertices within `snap_distance` of G = 0 onto that curve,
// flags all of them in `is_boundary`. Leaves unused vertices (remove_unreferenced_vertices).
ClipCutStats cut_at_clip(Mesh& mesh, const Surface& surface, double snap_distance, int workers);

// Flags the vertices of edges that lie in one triangle only.
void flag_open_boundary(Mesh& mesh);

// Unit normal of triangle (a, b, c) times twice its area.
inline Vec3 area_normal(const Vec3& a, const Vec3& b, const Vec3& c) {
  return (b - a).cross(c - a);
}

// The angle (radians) at corner `at` of the triangle (at, p, q); atan2 of |u × w| and u · w
// stays accurate near 0 and π, where acos of the cosine does not.
inline double corner_angle(const Vec3& at, const Vec3& p, const Vec3& q) {
  const Vec3 u = p - at, w = q - at;
  return std::atan2(u.cross(w).norm(), u.dot(w));
}

// Mean ratio 4√3·area / Σ edge², 1 for an equilateral triangle, 0 for a degenerate one.
inline double mean_ratio(const Vec3& a, const Vec3& b, const Vec3& c) {
  const double sum = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
  return sum > 0 ? 3.4641016151377544 * area_normal(a, b, c).norm() / sum : 0.0;
}

// The improver's set-up (improve_setup.cpp): throws InvalidArgument naming a bad option; the
// workers a step uses for `vertices` vertices (`requested` 0: as many as pay off).
void check_improve_options(const ImproveOptions& o);
int improver_workers(int requested, size_t vertices);
// The mean length of the edges in the improver's neighbour lists (`cap` slots per vertex).
double improver_mean_edge(const std::vector<Vec3>& positions, const std::vector<std::uint32_t>& nbr,
                          const std::vector<std::uint32_t>& nbr_count, int cap, int workers);

}  // namespace zeroset::detail
