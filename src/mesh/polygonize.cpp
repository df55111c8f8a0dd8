#include "zeroset/mesh/polygonize.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <unordered_map>
#include <utility>

#include "mesh_detail.h"
#include "polygonize_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/mesh/mesh_ops.h"

namespace zeroset {
namespace {

// Where F vanishes exactly at a grid node (integer surfaces on grids with rational spacing:
// the cone's Pythagorean triples, planes through nodes, a curve along a grid line), every
// crossing edge that ends there puts its vertex on the node. Those vertices become one, as
// the node is one point of the surface; triangles left with two corners alike go, and so
// does a pair of triangles on the same three vertices (a sheet of no thickness, as marching
// cubes makes around a node where F touches zero). Vertices within 1e-9 cells of a node are
// on it up to the rounding of the refinement. Returns the vertices merged.
long long weld_grid_nodes(Mesh& mesh, const detail::Grid& g) {
  using detail::kNone;
  const double tol = 1e-9 * g.h;
  std::unordered_map<long long, std::uint32_t> node_vertex;
  std::vector<std::uint32_t> remap(mesh.positions.size(), kNone);
  long long merged = 0;
  for (size_t v = 0; v < mesh.positions.size(); ++v) {
    Vec3& p = mesh.positions[v];
    long long idx[3];
    for (int a = 0; a < 3; ++a) idx[a] = std::llround((p[a] - g.lo[a]) / g.h);
    const Vec3 node = g.node(idx[0], idx[1], idx[2]);
    if (!((p - node).norm() <= tol)) continue;
    p = node;
    const long long key = (idx[2] * g.ny() + idx[1]) * g.nx() + idx[0];
    const auto [it, fresh] = node_vertex.try_emplace(key, static_cast<std::uint32_t>(v));
    if (!fresh) remap[v] = it->second, ++merged;
  }
  if (merged == 0) return 0;
  std::vector<std::uint8_t> welded(mesh.positions.size(), 0);
  for (size_t v = 0; v < remap.size(); ++v)
    if (remap[v] != kNone) welded[v] = welded[remap[v]] = 1;
  for (auto& t : mesh.triangles)
    for (std::uint32_t& v : t)
      if (remap[v] != kNone) v = remap[v];
  std::erase_if(mesh.triangles,
                [](const auto& t) { return t[0] == t[1] || t[1] == t[2] || t[2] == t[0]; });
  // Triangles on the same three vertices, in either orientation, come in pairs that cancel.
  std::unordered_map<std::uint64_t, std::vector<size_t>> by_corners;
  auto corners_key = [](std::array<std::uint32_t, 3> t) {
    std::sort(t.begin(), t.end());
    return (static_cast<std::uint64_t>(t[0]) * 0x9E3779B97F4A7C15ull) ^
           (static_cast<std::uint64_t>(t[1]) << 21) ^ (static_cast<std::uint64_t>(t[2]) << 42);
  };
  auto same_corners = [](std::array<std::uint32_t, 3> a, std::array<std::uint32_t, 3> b) {
    std::sort(a.begin(), a.end());
    std::sort(b.begin(), b.end());
    return a == b;
  };
  std::vector<std::uint8_t> gone(mesh.triangles.size(), 0);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (!welded[tri[0]] && !welded[tri[1]] && !welded[tri[2]]) continue;  // no twin possible
    auto& list = by_corners[corners_key(mesh.triangles[t])];
    auto twin = std::find_if(list.begin(), list.end(), [&](size_t o) {
      return same_corners(mesh.triangles[o], mesh.triangles[t]);
    });
    if (twin == list.end()) {
      list.push_back(t);
      continue;
    }
    gone[t] = gone[*twin] = 1;
    list.erase(twin);
  }
  size_t kept = 0;
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    if (!gone[t]) mesh.triangles[kept++] = mesh.triangles[t];
  mesh.triangles.resize(kept);
  return merged;
}

// Leaves out the triangles with a corner where no vertex could be placed (no_vertex(): an edge
// with an end where F is not finite, or a pole); the vertices themselves go with the other
// unreferenced ones, before the clean-up sees them. Returns the triangles removed and counts
// those vertices.
long long drop_undefined(Mesh& mesh, long long& undefined_vertices) {
  std::vector<std::uint8_t> bad(mesh.positions.size(), 0);
  long long count = 0;
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    if (!mesh.positions[v].allFinite()) bad[v] = 1, ++count;
  undefined_vertices = count;
  if (count == 0) return 0;
  const size_t before = mesh.triangles.size();
  std::erase_if(mesh.triangles, [&](const auto& t) { return bad[t[0]] || bad[t[1]] || bad[t[2]]; });
  remove_unreferenced_vertices(mesh);
  return static_cast<long long>(before - mesh.triangles.size());
}

}  // namespace

Mesh polygonize(const Surface& surface, const PolygonizeOptions& options, PolygonizeStats* stats,
                std::stop_token stop) {
  using detail::Clock;
  using detail::seconds_since;
  const auto t_start = Clock::now();
  const detail::Grid g = detail::make_grid(surface, options);
  PolygonizeStats st;
  st.grid_bounds.lo = g.lo;
  st.grid_bounds.hi = g.node(g.cells[0], g.cells[1], g.cells[2]);
  for (int a = 0; a < 3; ++a)
    st.cells[static_cast<size_t>(a)] = static_cast<int>(g.cells[static_cast<size_t>(a)]);
  st.cell_size = g.h;
  st.sparse = detail::use_sparse(g, options);
  surface.field.require_parameters();
  const int workers = detail::worker_count(options.threads);

  std::optional<Polynomial> poly;
  if (options.polynomial_rows && surface.field.is_expandable()) poly = surface.field.polynomial();

  const Polynomial* p = poly ? &*poly : nullptr;
  detail::ExtractedMesh r = st.sparse
                                ? detail::extract_sparse(surface, g, options, p, workers, st, stop)
                                : detail::extract_dense(surface, g, options, p, workers, st, stop);
  if (stop.stop_requested()) return {};

  const auto t_clean = Clock::now();
  Mesh mesh;
  mesh.positions = std::move(r.positions);
  mesh.triangles = std::move(r.triangles);
  long long undefined_vertices = 0;
  st.undefined_triangles = drop_undefined(mesh, undefined_vertices);
  st.undefined_edges = undefined_vertices - st.pole_edges;
  st.welded_vertices = weld_grid_nodes(mesh, g);
  mesh.is_boundary.assign(mesh.positions.size(), 0);
  if (detail::clips(surface, options)) {
    const detail::ClipCutStats cs =
        detail::cut_at_clip(mesh, surface, options.clip_snap_fraction * g.h, workers);
    st.clip_cut_edges = cs.cut_edges;
    st.clip_snapped = cs.snapped;
  }
  if (stop.stop_requested()) return {};
  st.collapsed_edges =
      static_cast<long long>(collapse_short_edges(mesh, options.collapse_fraction * g.h));
  remove_unreferenced_vertices(mesh);
  detail::flag_open_boundary(mesh);
  if (options.compute_normals) compute_field_normals(mesh, surface, options.threads);
  st.seconds_cleanup = seconds_since(t_clean);
  st.seconds_total = seconds_since(t_start);
  if (stats) *stats = st;
  if (stop.stop_requested()) return {};
  return mesh;
}

}  // namespace zeroset
