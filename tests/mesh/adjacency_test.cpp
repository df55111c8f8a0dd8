#include <array>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "zeroset/error.h"
#include "zeroset/mesh/adjacency.h"

namespace zeroset {
namespace {

Mesh tetrahedron() {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  return m;
}

TEST(Adjacency, TetrahedronIsWatertightWithEulerCharacteristicTwo) {
  const MeshTopology t = mesh_topology(tetrahedron());
  EXPECT_TRUE(t.is_watertight());
  EXPECT_EQ(t.edges, 6u);
  EXPECT_EQ(t.euler_characteristic, 2);
}

TEST(Adjacency, RingsListEveryNeighbourOnce) {
  const MeshAdjacency a = build_adjacency(tetrahedron());
  for (std::uint32_t v = 0; v < 4; ++v) EXPECT_EQ(a.valence(v), 3u);
  EXPECT_EQ(a.neighbors.size(), 12u);
}

TEST(Adjacency, OpenTriangleHasThreeBoundaryEdges) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  const MeshTopology t = mesh_topology(m);
  EXPECT_EQ(t.boundary_edges, 3u);
  EXPECT_FALSE(t.is_watertight());
  EXPECT_EQ(t.euler_characteristic, 1);
}

TEST(Adjacency, DetectsMisorientedAndNonManifoldEdges) {
  Mesh m = tetrahedron();
  std::swap(m.triangles[0][1], m.triangles[0][2]);  // turn one face over
  EXPECT_GT(mesh_topology(m).misoriented_edges, 0u);
  Mesh fin = tetrahedron();
  fin.positions.push_back({1, 1, 1});
  fin.triangles.push_back({0, 1, 4});  // a third triangle on edge (0, 1)
  EXPECT_EQ(mesh_topology(fin).non_manifold_edges, 1u);
}

TEST(Adjacency, BoundaryEdgesAreTheEdgesInOneTriangle) {
  EXPECT_TRUE(boundary_edges(4, tetrahedron().triangles).empty());
  Mesh m = tetrahedron();
  m.triangles.pop_back();  // open the face (0, 3, 2)
  const auto open = boundary_edges(m.positions.size(), m.triangles);
  const std::vector<std::array<std::uint32_t, 2>> expected = {{0, 2}, {0, 3}, {2, 3}};
  EXPECT_EQ(open, expected);
  const MeshAdjacency adj = build_adjacency(m);
  size_t in_one = 0;
  for (std::uint32_t c : adj.edge_triangle_count) in_one += c == 1;
  EXPECT_EQ(in_one, open.size());
}

TEST(Adjacency, VertexTrianglesInIncreasingOrderOncePerCorner) {
  const VertexTriangles vt = build_vertex_triangles(4, tetrahedron().triangles);
  const std::vector<std::uint32_t> at0 = {0, 1, 3};
  EXPECT_EQ(std::vector<std::uint32_t>(vt.of(0).begin(), vt.of(0).end()), at0);
  for (std::uint32_t v = 0; v < 4; ++v) EXPECT_EQ(vt.count(v), 3u);
  const std::vector<std::array<std::uint32_t, 3>> degenerate = {{0, 1, 1}};
  EXPECT_EQ(build_vertex_triangles(2, degenerate).count(1), 2u);
}

TEST(Adjacency, RejectsTrianglesWithMissingVertices) {
  Mesh m = tetrahedron();
  m.triangles.push_back({0, 1, 9});
  EXPECT_THROW(build_adjacency(m), InvalidArgument);
  EXPECT_THROW(boundary_edges(m.positions.size(), m.triangles), InvalidArgument);
  EXPECT_THROW(build_vertex_triangles(m.positions.size(), m.triangles), InvalidArgument);
}

}  // namespace
}  // namespace zeroset
