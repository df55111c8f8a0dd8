#include "zeroset/mesh/adjacency.h"

#include <algorithm>
#include <functional>
#include <string>

#include "zeroset/error.h"

namespace zeroset {

namespace {

using Triangles = std::span<const std::array<std::uint32_t, 3>>;

void check_vertices(size_t nv, Triangles triangles) {
  for (size_t t = 0; t < triangles.size(); ++t)
    for (std::uint32_t v : triangles[t])
      if (v >= nv)
        throw InvalidArgument(
            "triangle " + std::to_string(t), std::to_string(v),
            "refers to a vertex the mesh does not have (" + std::to_string(nv) + " vertices)");
}

// Every directed triangle edge a → b (a ≠ b) bucketed by its smaller vertex, in triangle
// order: bucket v is half[start[v] .. start[v + 1]), entries make(max(a, b), t).
template <class Half, class Make>
void bucket_edges(size_t nv, Triangles triangles, std::vector<std::uint32_t>& start,
                  std::vector<Half>& half, Make make) {
  start.assign(nv + 1, 0);
  for (const auto& tri : triangles)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[static_cast<size_t>(k)],
                          b = tri[static_cast<size_t>((k + 1) % 3)];
      if (a != b) ++start[std::min(a, b) + 1];
    }
  for (size_t v = 0; v < nv; ++v) start[v + 1] += start[v];
  half.resize(start[nv]);
  std::vector<std::uint32_t> fill(start.begin(), start.end() - 1);
  for (size_t t = 0; t < triangles.size(); ++t) {
    const auto& tri = triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[static_cast<size_t>(k)],
                          b = tri[static_cast<size_t>((k + 1) % 3)];
      if (a == b) continue;
      half[fill[std::min(a, b)]++] = make(std::max(a, b), static_cast<std::uint32_t>(t));
    }
  }
}

// Sorts one bucket. Buckets mostly hold a handful of entries: insertion sort beats
// std::sort's set-up.
template <class T, class Less>
void sort_bucket(T* b, T* e, Less less) {
  if (e - b < 2) return;  // also an empty bucket of an empty mesh: b is null, b + 1 undefined
  if (e - b > 32) {
    std::sort(b, e, less);
    return;
  }
  for (T* h = b + 1; h < e; ++h) {
    const T x = *h;
    T* g = h;
    for (; g > b && less(x, g[-1]); --g) *g = g[-1];
    *g = x;
  }
}

}  // namespace

MeshAdjacency build_adjacency(const Mesh& mesh) {
  return build_adjacency(mesh.positions.size(), mesh.triangles);
}

MeshAdjacency build_adjacency(size_t vertex_count,
                              std::span<const std::array<std::uint32_t, 3>> triangles) {
  const size_t nv = vertex_count;
  check_vertices(nv, triangles);
  // Bucket every directed triangle edge by its smaller vertex, then sort each small bucket.
  struct Half {
    std::uint32_t other;
    std::uint32_t triangle;
  };
  std::vector<std::uint32_t> start;
  std::vector<Half> half;
  bucket_edges(nv, triangles, start, half, [](std::uint32_t other, std::uint32_t t) {
    return Half{other, t};
  });
  MeshAdjacency adj;
  adj.edges.reserve(half.size() / 2 + 1);
  adj.edge_triangles.reserve(half.size() / 2 + 1);
  adj.edge_triangle_count.reserve(half.size() / 2 + 1);
  std::vector<std::uint32_t> degree(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    auto* b = half.data() + start[v];
    auto* e = half.data() + start[v + 1];
    sort_bucket(b, e, [](const Half& l, const Half& r) {
      return l.other != r.other ? l.other < r.other : l.triangle < r.triangle;
    });
    for (auto* h = b; h != e;) {
      auto* g = h;
      std::array<std::uint32_t, 2> tris = {MeshAdjacency::kNone, MeshAdjacency::kNone};
      std::uint32_t count = 0;
      for (; g != e && g->other == h->other; ++g) {
        if (count < 2) tris[count] = g->triangle;
        ++count;
      }
      adj.edges.push_back({static_cast<std::uint32_t>(v), h->other});
      adj.edge_triangles.push_back(tris);
      adj.edge_triangle_count.push_back(count);
      ++degree[v];
      ++degree[h->other];
      h = g;
    }
  }
  adj.neighbor_offsets.assign(nv + 1, 0);
  for (size_t v = 0; v < nv; ++v) adj.neighbor_offsets[v + 1] = adj.neighbor_offsets[v] + degree[v];
  adj.neighbors.resize(adj.neighbor_offsets[nv]);
  std::vector<std::uint32_t> pos(adj.neighbor_offsets.begin(), adj.neighbor_offsets.end() - 1);
  // The edges are sorted by (a, b), so each ring receives first its smaller neighbours in
  // increasing order, then its larger ones in increasing order: it comes out sorted.
  for (const auto& [a, b] : adj.edges) {
    adj.neighbors[pos[a]++] = b;
    adj.neighbors[pos[b]++] = a;
  }
  return adj;
}

std::vector<std::array<std::uint32_t, 2>> boundary_edges(
    size_t vertex_count, std::span<const std::array<std::uint32_t, 3>> triangles) {
  const size_t nv = vertex_count;
  check_vertices(nv, triangles);
  // Only how many triangles hold each edge matters: the buckets keep just the other vertex.
  std::vector<std::uint32_t> start, other;
  bucket_edges(nv, triangles, start, other, [](std::uint32_t o, std::uint32_t) { return o; });
  std::vector<std::array<std::uint32_t, 2>> edges;
  for (size_t v = 0; v < nv; ++v) {
    std::uint32_t* b = other.data() + start[v];
    std::uint32_t* e = other.data() + start[v + 1];
    sort_bucket(b, e, std::less<>());
    for (std::uint32_t* h = b; h != e;) {
      std::uint32_t* g = h;
      while (g != e && *g == *h) ++g;
      if (g - h == 1) edges.push_back({static_cast<std::uint32_t>(v), *h});
      h = g;
    }
  }
  return edges;
}

VertexTriangles build_vertex_triangles(size_t vertex_count,
                                       std::span<const std::array<std::uint32_t, 3>> triangles) {
  const size_t nv = vertex_count;
  check_vertices(nv, triangles);
  VertexTriangles vt;
  vt.offsets.assign(nv + 1, 0);
  for (const auto& tri : triangles)
    for (std::uint32_t v : tri) ++vt.offsets[v + 1];
  for (size_t v = 0; v < nv; ++v) vt.offsets[v + 1] += vt.offsets[v];
  vt.triangles.resize(3 * triangles.size());
  std::vector<std::uint32_t> fill(vt.offsets.begin(), vt.offsets.end() - 1);
  for (size_t t = 0; t < triangles.size(); ++t)
    for (std::uint32_t v : triangles[t]) vt.triangles[fill[v]++] = static_cast<std::uint32_t>(t);
  return vt;
}

MeshTopology mesh_topology(const Mesh& mesh) {
  const MeshAdjacency adj = build_adjacency(mesh);
  MeshTopology t;
  t.triangles = mesh.triangles.size();
  t.edges = adj.edges.size();
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    t.vertices += adj.valence(static_cast<std::uint32_t>(v)) > 0;
  for (const auto& tri : mesh.triangles)
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]) ++t.degenerate_triangles;
  auto direction = [&](std::uint32_t tri, std::uint32_t a, std::uint32_t b) {
    const auto& v = mesh.triangles[tri];
    for (int k = 0; k < 3; ++k)
      if (v[static_cast<size_t>(k)] == a && v[static_cast<size_t>((k + 1) % 3)] == b) return 1;
    return -1;
  };
  for (size_t e = 0; e < adj.edges.size(); ++e) {
    const std::uint32_t c = adj.edge_triangle_count[e];
    if (c == 1) ++t.boundary_edges;
    if (c > 2) ++t.non_manifold_edges;
    if (c == 2) {
      const auto [a, b] = adj.edges[e];
      if (direction(adj.edge_triangles[e][0], a, b) == direction(adj.edge_triangles[e][1], a, b))
        ++t.misoriented_edges;
    }
  }
  t.euler_characteristic = static_cast<long long>(t.vertices) - static_cast<long long>(t.edges) +
                           static_cast<long long>(t.triangles);
  return t;
}

}  // namespace zeroset
