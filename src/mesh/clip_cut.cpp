// Cutting a mesh at the clip surface (polygonize.h).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <Eigen/Dense>

#include "mesh_detail.h"
#include "zeroset/detail/bracket.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/mesh/adjacency.h"
#include "zeroset/surface/analysis.h"

namespace zeroset::detail {
namespace {

enum Side : std::uint8_t { kIn = 0, kOn = 1, kOut = 2 };

// |cos| of the angle between ∇F and ∇G above which F = 0 counts as running along the clip.
constexpr double kSheetCosine = 0.9;

// The point where G = 0 on the segment from `in` (G < 0) to `out` (G > 0), by bisection
// with a secant guess (G is 1-Lipschitz and piecewise smooth for spheres and planes).
Vec3 clip_crossing(const Clip& clip, const Vec3& in, const Vec3& out) {
  const double t = secant_bisection([&](double s) { return clip.value(in + s * (out - in)); },
                                    clip.value(in), clip.value(out));
  return in + t * (out - in);
}

}  // namespace

void flag_open_boundary(Mesh& mesh) {
  mesh.is_boundary.resize(mesh.positions.size(), 0);
  for (const auto& [a, b] : boundary_edges(mesh.positions.size(), mesh.triangles))
    mesh.is_boundary[a] = mesh.is_boundary[b] = 1;
}

ClipCutStats cut_at_clip(Mesh& mesh, const Surface& surface, double snap_distance, int workers) {
  ClipCutStats st;
  const Clip& clip = surface.clip;
  const long long nv = static_cast<long long>(mesh.positions.size());
  std::vector<double> g(static_cast<size_t>(nv));
  std::vector<std::uint8_t> side(static_cast<size_t>(nv));
  detail::ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(static)
  for (long long v = 0; v < nv; ++v)
    trap.run([&] {
      const double gv = clip.value(mesh.positions[static_cast<size_t>(v)]);
      g[static_cast<size_t>(v)] = gv;
      side[static_cast<size_t>(v)] = std::abs(gv) <= snap_distance ? kOn : gv < 0 ? kIn : kOut;
    });
  trap.rethrow();
  // Only triangles with a vertex on or outside the clip can change, and every edge that
  // matters below (one with a vertex on the clip, or one that crosses it) has all its
  // triangles among them: connectivity over that band is enough.
  // A triangle with every vertex on the clip lies in the clip surface. It belongs to the mesh
  // only where F = 0 runs along the clip there (∇F parallel to ∇G at its centre); where the
  // surface crosses the clip, it is a sliver between boundary vertices (a grid face on a box
  // clip's plane, a vertex snapped next to its neighbours), often turned against ∇F.
  EvaluatorPool pool(surface.field, workers);
  std::vector<std::array<std::uint32_t, 3>> band;
  // Per triangle (and per band triangle): one with every vertex on the clip that stays.
  std::vector<std::uint8_t> all_on_kept(mesh.triangles.size(), 0), band_all_on_kept;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (side[tri[0]] == kIn && side[tri[1]] == kIn && side[tri[2]] == kIn) continue;
    if (side[tri[0]] == kOn && side[tri[1]] == kOn && side[tri[2]] == kOn) {
      const Vec3 c =
          (mesh.positions[tri[0]] + mesh.positions[tri[1]] + mesh.positions[tri[2]]) / 3.0;
      Vec3 gf, gg;
      pool.local().value_gradient(c, gf);
      clip.value_gradient(c, gg);
      const double norms = gf.norm() * gg.norm();
      all_on_kept[t] = !(norms > 0) || std::abs(gf.dot(gg)) >= kSheetCosine * norms;
    }
    band.push_back(tri);
    band_all_on_kept.push_back(all_on_kept[t]);
  }
  const MeshAdjacency adj = build_adjacency(mesh.positions.size(), band);
  auto kept = [&](std::uint32_t t) {
    const auto& tri = band[t];
    bool any_in = false, all_on = true;
    for (std::uint32_t v : tri) any_in |= side[v] == kIn, all_on &= side[v] == kOn;
    return any_in || (all_on && band_all_on_kept[t]);
  };
  // A vertex moved onto the clip must keep a single fan of triangles: where the clip curve
  // passes it so that kept and dropped triangles alternate, it is cut normally instead.
  for (int round = 0; round < 8; ++round) {
    std::vector<std::uint8_t> fan_edges(static_cast<size_t>(nv), 0);
    for (size_t e = 0; e < adj.edges.size(); ++e) {
      int k = 0;
      for (std::uint32_t t : adj.edge_triangles[e])
        if (t != MeshAdjacency::kNone) k += kept(t);
      if (k != 1) continue;
      for (std::uint32_t v : adj.edges[e])
        if (side[v] == kOn && fan_edges[v] < 255) ++fan_edges[v];
    }
    bool changed = false;
    for (long long v = 0; v < nv; ++v)
      if (side[static_cast<size_t>(v)] == kOn && fan_edges[static_cast<size_t>(v)] > 2) {
        side[static_cast<size_t>(v)] = g[static_cast<size_t>(v)] < 0 ? kIn : kOut;
        changed = true;
      }
    if (!changed) break;
  }

  // New vertices on edges from inside to outside, numbered after the old ones.
  std::vector<std::uint32_t> edge_vertex(adj.edges.size(), MeshAdjacency::kNone);
  std::vector<size_t> cut_edges;
  for (size_t e = 0; e < adj.edges.size(); ++e) {
    const auto [a, b] = adj.edges[e];
    if ((side[a] == kIn && side[b] == kOut) || (side[a] == kOut && side[b] == kIn)) {
      edge_vertex[e] = static_cast<std::uint32_t>(mesh.positions.size() + cut_edges.size());
      cut_edges.push_back(e);
    }
  }
  std::vector<long long> snapped;
  for (long long v = 0; v < nv; ++v)
    if (side[static_cast<size_t>(v)] == kOn) snapped.push_back(v);
  mesh.positions.resize(mesh.positions.size() + cut_edges.size());
  mesh.is_boundary.resize(mesh.positions.size(), 0);

  const long long ncut = static_cast<long long>(cut_edges.size());
#pragma omp parallel for num_threads(workers) schedule(dynamic, 64)
  for (long long c = 0; c < ncut; ++c)
    trap.run([&] {
      const auto [a, b] = adj.edges[cut_edges[static_cast<size_t>(c)]];
      const Vec3& pa = mesh.positions[a];
      const Vec3& pb = mesh.positions[b];
      const Vec3 x = side[a] == kIn ? clip_crossing(clip, pa, pb) : clip_crossing(clip, pb, pa);
      mesh.positions[static_cast<size_t>(nv + c)] =
          project_onto_clip_curve(pool.local(), clip, x, (pb - pa).norm());
    });
  trap.rethrow();
  const long long nsnap = static_cast<long long>(snapped.size());
#pragma omp parallel for num_threads(workers) schedule(dynamic, 64)
  for (long long s = 0; s < nsnap; ++s)
    trap.run([&] {
      Vec3& p = mesh.positions[static_cast<size_t>(snapped[static_cast<size_t>(s)])];
      p = project_onto_clip_curve(pool.local(), clip, p, 4 * snap_distance + 1e-300);
    });
  trap.rethrow();
  for (long long v : snapped) mesh.is_boundary[static_cast<size_t>(v)] = 1;
  for (long long c = 0; c < ncut; ++c) mesh.is_boundary[static_cast<size_t>(nv + c)] = 1;
  st.cut_edges = ncut;
  st.snapped = nsnap;

  // Clip every triangle (Sutherland–Hodgman against G ≤ 0, vertices on G = 0 kept as they are).
  auto cut_vertex = [&](std::uint32_t a, std::uint32_t b) {
    const std::array<std::uint32_t, 2> key = {std::min(a, b), std::max(a, b)};
    const auto it = std::lower_bound(adj.edges.begin(), adj.edges.end(), key);
    return edge_vertex[static_cast<size_t>(it - adj.edges.begin())];
  };
  std::vector<std::array<std::uint32_t, 3>> out;
  out.reserve(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    bool any_in = false, any_out = false, all_on = true;
    for (std::uint32_t v : tri)
      any_in |= side[v] == kIn, any_out |= side[v] == kOut, all_on &= side[v] == kOn;
    if (all_on) {
      if (all_on_kept[t]) out.push_back(tri);
      continue;
    }
    if (!any_out) {
      out.push_back(tri);
      continue;
    }
    if (!any_in) continue;
    std::uint32_t poly[4];
    int n = 0;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[static_cast<size_t>(k)],
                          b = tri[static_cast<size_t>((k + 1) % 3)];
      if (side[a] != kOut) poly[n++] = a;
      if ((side[a] == kIn && side[b] == kOut) || (side[a] == kOut && side[b] == kIn))
        poly[n++] = cut_vertex(a, b);
    }
    if (n == 3) {
      out.push_back({poly[0], poly[1], poly[2]});
    } else if (n == 4) {
      const auto& P = mesh.positions;
      const double q02 = std::min(mean_ratio(P[poly[0]], P[poly[1]], P[poly[2]]),
                                  mean_ratio(P[poly[0]], P[poly[2]], P[poly[3]]));
      const double q13 = std::min(mean_ratio(P[poly[0]], P[poly[1]], P[poly[3]]),
                                  mean_ratio(P[poly[1]], P[poly[2]], P[poly[3]]));
      if (q02 >= q13) {
        out.push_back({poly[0], poly[1], poly[2]});
        out.push_back({poly[0], poly[2], poly[3]});
      } else {
        out.push_back({poly[0], poly[1], poly[3]});
        out.push_back({poly[1], poly[2], poly[3]});
      }
    }
  }
  mesh.triangles = std::move(out);
  return st;
}

}  // namespace zeroset::detail
