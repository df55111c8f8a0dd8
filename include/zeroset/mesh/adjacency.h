#pragma once
/// Mesh connectivity built on demand (docs/architecture.md, "Modules"): unique edges with the
/// triangles on each side, vertex rings, and a topology summary (closedness, Euler characteristic).
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "zeroset/mesh/mesh.h"

namespace zeroset {

/// Undirected edges and vertex rings of a mesh. A plain value: it does not follow later
/// changes of the mesh it was built from.
struct MeshAdjacency {
  static constexpr std::uint32_t kNone = 0xffffffffu;

  /// Unique undirected edges (a < b), sorted by (a, b).
  std::vector<std::array<std::uint32_t, 2>> edges;
  /// The first two triangles that contain each edge (kNone where there are fewer).
  std::vector<std::array<std::uint32_t, 2>> edge_triangles;
  /// How many triangles contain each edge: 1 on a boundary, 2 inside, more when non-manifold.
  std::vector<std::uint32_t> edge_triangle_count;
  /// Vertex rings in CSR form: the neighbours of v are
  /// neighbors[neighbor_offsets[v] .. neighbor_offsets[v + 1]), sorted.
  std::vector<std::uint32_t> neighbor_offsets;
  std::vector<std::uint32_t> neighbors;

  size_t valence(std::uint32_t v) const { return neighbor_offsets[v + 1] - neighbor_offsets[v]; }
};

/// Builds the adjacency in O(V + T) time and memory (bucketed by the smaller vertex index).
/// Throws InvalidArgument when a triangle refers to a vertex that does not exist.
MeshAdjacency build_adjacency(const Mesh& mesh);
/// The same for a set of triangles over `vertex_count` vertices (part of a mesh, say: edge
/// triangle indices then refer to positions in `triangles`).
MeshAdjacency build_adjacency(size_t vertex_count,
                              std::span<const std::array<std::uint32_t, 3>> triangles);

/// The edges that lie in exactly one triangle (the mesh's open border), sorted by (a, b), a < b.
/// The same edges as those of `build_adjacency` with one triangle, found without storing the
/// triangles or the rings. Throws InvalidArgument like `build_adjacency`.
std::vector<std::array<std::uint32_t, 2>> boundary_edges(
    size_t vertex_count, std::span<const std::array<std::uint32_t, 3>> triangles);

/// The triangles around each vertex in CSR form: those of v are
/// triangles[offsets[v] .. offsets[v + 1]), in increasing order, a triangle once per corner it
/// has at v (so twice at the repeated vertex of a degenerate triangle). A plain value like
/// MeshAdjacency.
struct VertexTriangles {
  std::vector<std::uint32_t> offsets;
  std::vector<std::uint32_t> triangles;

  size_t count(std::uint32_t v) const { return offsets[v + 1] - offsets[v]; }
  std::span<const std::uint32_t> of(std::uint32_t v) const {
    return {triangles.data() + offsets[v], count(v)};
  }
};

/// Builds the vertex → triangle lists in O(V + T). Throws InvalidArgument like
/// `build_adjacency`.
VertexTriangles build_vertex_triangles(size_t vertex_count,
                                       std::span<const std::array<std::uint32_t, 3>> triangles);

/// Counts that decide whether a mesh is a closed, consistently oriented 2-manifold.
struct MeshTopology {
  size_t vertices = 0;  ///< vertices used by at least one triangle
  size_t edges = 0;
  size_t triangles = 0;
  size_t boundary_edges = 0;           ///< in exactly one triangle
  size_t non_manifold_edges = 0;       ///< in three or more triangles
  size_t misoriented_edges = 0;        ///< interior edges traversed twice in the same direction
  size_t degenerate_triangles = 0;     ///< a vertex index repeated
  long long euler_characteristic = 0;  ///< V − E + T over the used vertices

  /// Every edge in exactly two triangles, each traversed once in each direction.
  bool is_watertight() const {
    return boundary_edges == 0 && non_manifold_edges == 0 && misoriented_edges == 0 &&
           degenerate_triangles == 0;
  }
};

/// Topology summary. Cost: one `build_adjacency`.
MeshTopology mesh_topology(const Mesh& mesh);

}  // namespace zeroset
