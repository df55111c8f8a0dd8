#include "zeroset/mesh/mesh_ops.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <vector>

#include "mesh_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/mesh/adjacency.h"

namespace zeroset {

size_t remove_unreferenced_vertices(Mesh& mesh) {
  const size_t nv = mesh.positions.size();
  std::vector<std::uint32_t> remap(nv, 0xffffffffu);
  for (const auto& tri : mesh.triangles)
    for (std::uint32_t v : tri) remap[v] = 0;
  for (const MeshCurve& c : mesh.curves)
    for (std::uint32_t v : c.vertices) remap[v] = 0;
  std::uint32_t next = 0;
  for (size_t v = 0; v < nv; ++v)
    if (remap[v] == 0) {
      remap[v] = next;
      mesh.positions[next] = mesh.positions[v];
      if (mesh.is_boundary.size() == nv) mesh.is_boundary[next] = mesh.is_boundary[v];
      if (mesh.normals.size() == nv) mesh.normals[next] = mesh.normals[v];
      ++next;
    }
  for (auto& tri : mesh.triangles)
    for (std::uint32_t& v : tri) v = remap[v];
  for (MeshCurve& c : mesh.curves)
    for (std::uint32_t& v : c.vertices) v = remap[v];
  mesh.positions.resize(next);
  if (mesh.is_boundary.size() == nv) mesh.is_boundary.resize(next);
  if (mesh.normals.size() == nv) mesh.normals.resize(next);
  return nv - next;
}

size_t collapse_short_edges(Mesh& mesh, double min_length) {
  using detail::kNone;
  auto& tris = mesh.triangles;
  std::erase_if(tris, [](const auto& t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; });
  if (!(min_length > 0)) return 0;
  const auto& P = mesh.positions;
  const size_t nv = P.size(), nt = tris.size();
  std::vector<std::tuple<double, std::uint32_t, std::uint32_t>> short_edges;
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = t[static_cast<size_t>(k)], b = t[static_cast<size_t>((k + 1) % 3)];
      const double len = (P[a] - P[b]).norm();
      if (len < min_length) short_edges.emplace_back(len, std::min(a, b), std::max(a, b));
    }
  if (short_edges.empty()) return 0;
  std::sort(short_edges.begin(), short_edges.end());
  short_edges.erase(std::unique(short_edges.begin(), short_edges.end()), short_edges.end());

  // Vertex → triangles of the original mesh; a collapsed vertex's list is reached through the
  // member chain of the vertex it was merged into.
  const VertexTriangles vt = build_vertex_triangles(nv, tris);
  std::vector<std::uint32_t> parent(nv), member_next(nv, kNone), member_tail(nv);
  for (size_t v = 0; v < nv; ++v) parent[v] = member_tail[v] = static_cast<std::uint32_t>(v);
  std::vector<std::uint8_t> alive(nt, 1);
  std::vector<std::uint8_t> fixed(nv, 0);
  if (mesh.is_boundary.size() == nv) fixed = mesh.is_boundary;
  auto find = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  auto ring = [&](std::uint32_t u, std::vector<std::uint32_t>& out) {
    out.clear();
    for (std::uint32_t m = u; m != kNone; m = member_next[m])
      for (std::uint32_t t : vt.of(m))
        if (alive[t]) out.push_back(t);
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  };
  auto mapped = [&](std::uint32_t t, int k) { return find(tris[t][static_cast<size_t>(k)]); };
  auto contains = [&](std::uint32_t t, std::uint32_t v) {
    return mapped(t, 0) == v || mapped(t, 1) == v || mapped(t, 2) == v;
  };
  // Neighbours of u with how many of u's triangles hold the edge (1: on the mesh border).
  auto neighbours = [&](std::uint32_t u, const std::vector<std::uint32_t>& ring_u,
                        std::vector<std::pair<std::uint32_t, int>>& out) {
    out.clear();
    for (std::uint32_t t : ring_u)
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t w = mapped(t, k);
        if (w == u) continue;
        auto it = std::find_if(out.begin(), out.end(), [&](const auto& p) { return p.first == w; });
        if (it == out.end())
          out.push_back({w, 1});
        else
          ++it->second;
      }
  };
  std::vector<std::uint32_t> ring_u, ring_v, shared;
  std::vector<std::pair<std::uint32_t, int>> nb_u, nb_v;
  size_t collapsed = 0;
  for (const auto& [len0, a, b] : short_edges) {
    const std::uint32_t u = find(a), v = find(b);
    if (u == v || (P[u] - P[v]).norm() >= min_length) continue;
    ring(u, ring_u);
    ring(v, ring_v);
    shared.clear();
    for (std::uint32_t t : ring_u)
      if (contains(t, v)) shared.push_back(t);
    if (shared.empty() || shared.size() > 2) continue;
    const bool border_edge = shared.size() == 1;
    neighbours(u, ring_u, nb_u);
    neighbours(v, ring_v, nb_v);
    // Link condition: the common neighbours are exactly the opposite corners of `shared`.
    size_t common = 0;
    bool link_ok = true;
    for (const auto& neighbour : nb_u) {
      const std::uint32_t w = neighbour.first;  // a name of its own: lambdas capture it
      if (w == v) continue;
      if (std::none_of(nb_v.begin(), nb_v.end(), [&](const auto& p) { return p.first == w; }))
        continue;
      ++common;
      link_ok &= std::any_of(shared.begin(), shared.end(),
                             [&](std::uint32_t t) { return contains(t, w); });
    }
    if (!link_ok || common != shared.size()) continue;
    const bool border_u =
        std::any_of(nb_u.begin(), nb_u.end(), [](const auto& p) { return p.second == 1; });
    const bool border_v =
        std::any_of(nb_v.begin(), nb_v.end(), [](const auto& p) { return p.second == 1; });
    if (border_u && border_v && !border_edge) continue;
    const bool hold_u = fixed[u] || border_u, hold_v = fixed[v] || border_v;
    if (hold_u && hold_v && !border_edge) continue;  // would pinch the mesh
    const std::uint32_t keep = hold_v && !hold_u ? v : u;
    const std::uint32_t gone = keep == u ? v : u;
    // No remaining triangle of the removed vertex may turn over or collapse. Merging two
    // vertices at one point up to rounding (several cell edges that end in an exact zero of F
    // at a grid node) changes no triangle's shape, so it needs no check; the zero-area
    // triangles around such a point, whose orientation no check could judge, would refuse it.
    const bool same_point = (P[u] - P[v]).norm() <= 1e-9 * min_length;
    bool geometry_ok = true;
    for (std::uint32_t t : (gone == u ? ring_u : ring_v)) {
      if (same_point) break;
      if (std::find(shared.begin(), shared.end(), t) != shared.end()) continue;
      Vec3 before[3], after[3];
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t w = mapped(t, k);
        before[k] = P[w];
        after[k] = w == gone ? P[keep] : P[w];
      }
      const Vec3 n0 = detail::area_normal(before[0], before[1], before[2]);
      const Vec3 n1 = detail::area_normal(after[0], after[1], after[2]);
      if (!(n1.dot(n0) > 0)) {
        geometry_ok = false;
        break;
      }
    }
    if (!geometry_ok) continue;
    for (std::uint32_t t : shared) alive[t] = 0;
    parent[gone] = keep;
    member_next[member_tail[keep]] = gone;
    member_tail[keep] = member_tail[gone];
    fixed[keep] = fixed[keep] || fixed[gone];
    ++collapsed;
  }
  std::vector<std::array<std::uint32_t, 3>> out;
  out.reserve(nt);
  for (size_t t = 0; t < nt; ++t)
    if (alive[t])
      out.push_back({mapped(static_cast<std::uint32_t>(t), 0),
                     mapped(static_cast<std::uint32_t>(t), 1),
                     mapped(static_cast<std::uint32_t>(t), 2)});
  tris = std::move(out);
  if (mesh.is_boundary.size() == nv)
    for (size_t v = 0; v < nv; ++v)
      mesh.is_boundary[v] = fixed[find(static_cast<std::uint32_t>(v))];
  return collapsed;
}

void compute_field_normals(Mesh& mesh, const Surface& surface, int threads) {
  const int workers = detail::worker_count(threads);
  const long long nv = static_cast<long long>(mesh.positions.size());
  mesh.normals.assign(static_cast<size_t>(nv), Vec3::Zero());
  detail::EvaluatorPool pool(surface.field, workers);
  std::vector<double> f;
  std::vector<Vec3> g;
  detail::values_gradients(pool, workers, mesh.positions, f, g);
  long long missing = 0;
  for (long long v = 0; v < nv; ++v) {
    const double len = g[static_cast<size_t>(v)].norm();
    if (len > 0 && std::isfinite(len))
      mesh.normals[static_cast<size_t>(v)] = g[static_cast<size_t>(v)] / len;
    else
      ++missing;
  }
  if (missing == 0) return;
  std::vector<Vec3> face_sum(static_cast<size_t>(nv), Vec3::Zero());
  for (const auto& t : mesh.triangles) {
    const Vec3 n =
        detail::area_normal(mesh.positions[t[0]], mesh.positions[t[1]], mesh.positions[t[2]]);
    for (std::uint32_t v : t) face_sum[v] += n;
  }
  for (long long v = 0; v < nv; ++v) {
    Vec3& n = mesh.normals[static_cast<size_t>(v)];
    if (n.squaredNorm() > 0) continue;
    const double len = face_sum[static_cast<size_t>(v)].norm();
    n = len > 0 ? Vec3(face_sum[static_cast<size_t>(v)] / len) : Vec3::UnitZ();
  }
}

}  // namespace zeroset
