// True crossings along singular curves: the tube around each crossing curve is cut out of the
// marching-cubes mesh and every half-sheet is joined to the curve's polyline by a strip of
// triangles. See docs/meshing.md ("Crossings").
#include "zeroset/mesh/crossings.h"

#include <fmt/core.h>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "crossings_detail.h"
#include "mesh_detail.h"
#include "zeroset/mesh/mesh_ops.h"
#include "zeroset/surface/analysis.h"
#include "zeroset/surface/singular_index.h"

namespace zeroset {
namespace {

using detail::CrossingCurves;
using detail::directed_edge_key;
using detail::edge_key;
using detail::kFreeEndReach;
using detail::kNone;
using detail::Network;
using detail::TubeCut;

Network build_network(const SingularSet& set, double spacing, bool isolated) {
  Network net;
  const double merge = 0.05 * spacing;
  // A hash of vertices would be faster; the curves have hundreds of vertices, not millions.
  for (const SingularCurve& sc : set.curves) {
    if (sc.kind == CurveKind::kDegenerate) continue;
    if (sc.kind == CurveKind::kIsolated && !isolated) continue;
    Network::Curve c;
    c.kind = sc.kind;
    c.closed = sc.closed;
    for (size_t i = 0; i < sc.points.size(); ++i) {
      const Vec3& p = sc.points[i];
      const std::uint32_t v = net.vertex_at(p, merge);
      if (!c.verts.empty() && c.verts.back() == v) {
        // A curve's end (on the clip, say) a hair past its last vertex: the vertex moves there.
        if (i + 1 == sc.points.size() && !sc.closed) net.pos[v] = p;
        continue;
      }
      c.verts.push_back(v);
    }
    if (c.closed && c.verts.front() != c.verts.back()) c.verts.push_back(c.verts.front());
    if (c.verts.size() < 2) continue;
    c.arc.assign(c.verts.size(), 0.0);
    for (size_t i = 1; i < c.verts.size(); ++i)
      c.arc[i] = c.arc[i - 1] + (net.pos[c.verts[i]] - net.pos[c.verts[i - 1]]).norm();
    if (c.kind == CurveKind::kCrossing)
      for (size_t i = 0; i + 1 < c.verts.size(); ++i) {
        net.adj[c.verts[i]].push_back(c.verts[i + 1]);
        net.adj[c.verts[i + 1]].push_back(c.verts[i]);
      }
    net.curves.push_back(std::move(c));
  }
  net.special.assign(net.pos.size(), 0);
  for (std::uint32_t v = 0; v < net.pos.size(); ++v) net.special[v] = net.adj[v].size() != 2;
  for (const SingularPoint& p : set.points)
    for (std::uint32_t v = 0; v < net.pos.size(); ++v)
      if ((net.pos[v] - p.position).norm() <= merge) net.special[v] = 1;
  net.free_end.assign(net.pos.size(), 0);
  net.clip_end.assign(net.pos.size(), 0);
  for (std::uint32_t v = 0; v < net.pos.size(); ++v) net.free_end[v] = net.adj[v].size() == 1;
  for (const SingularPoint& p : set.points)
    if (p.kind == SingularPointKind::kClipEnd)
      for (std::uint32_t v = 0; v < net.pos.size(); ++v)
        if ((net.pos[v] - p.position).norm() <= merge && net.adj[v].size() == 1)
          net.free_end[v] = 0, net.clip_end[v] = 1;
  return net;
}

// The strips span the tube's width, a few edge lengths, with no vertex inside: the sheets
// would have to stretch over the whole mesh to fill them, which the improver does only slowly.
// So every edge of a strip triangle longer than `limit` is split at its midpoint, moved onto
// F = 0 (onto the clip curve for an edge on the mesh's border), together with every triangle on
// it, until none is left; edges along the curves are never split. Returns the vertices added.
long long refine_strips(Mesh& mesh, size_t first_added, double limit, const Surface& surface,
                        const std::unordered_set<std::uint64_t>& curve_edges) {
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> on_edge;
  auto file = [&](std::uint32_t t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k)
      on_edge[edge_key(tri[static_cast<size_t>(k)], tri[static_cast<size_t>((k + 1) % 3)])]
          .push_back(t);
  };
  auto unfile = [&](std::uint32_t t) {
    const auto& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      auto& list =
          on_edge[edge_key(tri[static_cast<size_t>(k)], tri[static_cast<size_t>((k + 1) % 3)])];
      list.erase(std::remove(list.begin(), list.end(), t), list.end());
    }
  };
  // Only edges of strip triangles (and of their halves) are looked up, and their ends are strip
  // vertices or midpoints added here: the triangles with two strip vertices hold every such
  // edge of the input (the halves are filed as they are made). Filing all took most of this
  // step's time on a mesh of 10⁵ triangles.
  std::vector<std::uint8_t> in_strip(mesh.positions.size(), 0);
  for (size_t t = first_added; t < mesh.triangles.size(); ++t)
    for (std::uint32_t v : mesh.triangles[t]) in_strip[v] = 1;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    if (in_strip[tri[0]] + in_strip[tri[1]] + in_strip[tri[2]] >= 2) file(t);
  }
  Evaluator ev(surface.field);
  std::vector<std::uint32_t> queue;
  for (size_t t = first_added; t < mesh.triangles.size(); ++t)
    queue.push_back(static_cast<std::uint32_t>(t));
  long long added = 0;
  const auto& P = mesh.positions;
  // Each split halves an edge; the bound only guards against a cycle on degenerate input.
  const size_t max_splits = 16 * (mesh.triangles.size() - first_added) + 1024;
  for (size_t head = 0; head < queue.size() && static_cast<size_t>(added) < max_splits; ++head) {
    const std::uint32_t t = queue[head];
    const auto tri = mesh.triangles[t];
    const double area2 = (P[tri[1]] - P[tri[0]]).cross(P[tri[2]] - P[tri[0]]).norm();
    int longest = -1;
    double longest_len = limit;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tri[static_cast<size_t>(k)],
                          b = tri[static_cast<size_t>((k + 1) % 3)];
      const double len = (P[a] - P[b]).norm();
      if (len > longest_len && !curve_edges.count(edge_key(a, b))) longest = k, longest_len = len;
    }
    // A triangle with no area has no inside to fill: splitting it would not shorten its edges.
    if (longest < 0 || !(area2 > 1e-6 * longest_len * longest_len)) continue;
    const std::uint32_t a = tri[static_cast<size_t>(longest)],
                        b = tri[static_cast<size_t>((longest + 1) % 3)];
    const std::vector<std::uint32_t> sharing = on_edge[edge_key(a, b)];
    if (sharing.empty() || sharing.size() > 2) continue;
    Vec3 m = 0.5 * (P[a] + P[b]);
    const bool border = sharing.size() == 1 && mesh.is_boundary[a] && mesh.is_boundary[b];
    if (border) {
      m = project_onto_clip_curve(ev, surface.clip, m, 0.3 * longest_len);
    } else {
      Vec3 q = m;
      if (project_onto_surface(ev, q, 1e-13 * surface.scene_radius(), 0.3 * longest_len)) m = q;
    }
    if (!((m - P[a]).norm() > 0.25 * longest_len && (m - P[b]).norm() > 0.25 * longest_len))
      continue;
    // Both halves of every triangle on the edge must keep its side: near a singular curve the
    // projection can slide onto the curve, in line with the curve's own vertices, and a split
    // there would only make triangles without area.
    const bool halves_ok = std::all_of(sharing.begin(), sharing.end(), [&](std::uint32_t s) {
      const auto& old = mesh.triangles[s];
      const Vec3 n = (P[old[1]] - P[old[0]]).cross(P[old[2]] - P[old[0]]);
      for (int k = 0; k < 3; ++k) {
        const std::uint32_t v = old[static_cast<size_t>(k)];
        if (v != a && v != b) continue;
        Vec3 c[3] = {P[old[0]], P[old[1]], P[old[2]]};
        c[k] = m;  // the half that keeps the other end of the edge
        if (!(n.dot((c[1] - c[0]).cross(c[2] - c[0])) > 1e-3 * n.squaredNorm())) return false;
      }
      return true;
    });
    if (!halves_ok) continue;
    const std::uint32_t mid = static_cast<std::uint32_t>(mesh.positions.size());
    mesh.positions.push_back(m);
    mesh.is_boundary.push_back(border);
    ++added;
    for (std::uint32_t s : sharing) {
      unfile(s);
      auto old = mesh.triangles[s];
      int k = 0;  // the corner where the split edge starts
      while (!((old[static_cast<size_t>(k)] == a && old[static_cast<size_t>((k + 1) % 3)] == b) ||
               (old[static_cast<size_t>(k)] == b && old[static_cast<size_t>((k + 1) % 3)] == a)))
        ++k;
      const std::uint32_t x = old[static_cast<size_t>(k)],
                          y = old[static_cast<size_t>((k + 1) % 3)],
                          z = old[static_cast<size_t>((k + 2) % 3)];
      mesh.triangles[s] = {x, mid, z};
      const std::uint32_t t2 = static_cast<std::uint32_t>(mesh.triangles.size());
      mesh.triangles.push_back({mid, y, z});
      file(s);
      file(t2);
      if (s < first_added) continue;  // a marching-cubes triangle on a long rim edge: split only
      queue.push_back(s);
      queue.push_back(t2);
    }
  }
  return added;
}

double mean_edge_length(const Mesh& mesh) {
  const auto& p = mesh.positions;
  double sum = 0;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k)
      sum += (p[t[static_cast<size_t>(k)]] - p[t[static_cast<size_t>((k + 1) % 3)]]).norm();
  return sum / (3.0 * static_cast<double>(mesh.triangles.size()));
}

CrossingCurves crossing_curves_of(const Network& net) {
  CrossingCurves out;
  for (std::uint32_t c = 0; c < net.curves.size(); ++c) {
    if (net.curves[c].kind != CurveKind::kCrossing) continue;
    SingularCurve sc;
    for (std::uint32_t v : net.curves[c].verts) sc.points.push_back(net.pos[v]);
    out.set.curves.push_back(std::move(sc));
    out.curve_of.push_back(c);
  }
  return out;
}

// Cuts out the triangles with a corner closer than `tube` to a crossing curve. A kept tongue
// one triangle wide (along the bisector of a narrow sector of a sheet between two curves that
// meet) would be joined from each of its sides to the curve across it, and some of the joining
// triangles would turn over: triangles with two or three edges on the cut (the tongue's tip,
// then the next one) are cut too. Not near a free end of a curve (a pinch point), where the two
// sheets fold together and marching cubes has lost one of them: cutting there would take the
// other away too.
TubeCut cut_tube(const Mesh& mesh, const Network& net, const SingularSetIndex& index, double tube,
                 long long& removed_triangles) {
  const size_t nv = mesh.positions.size();
  std::vector<std::uint8_t> near(nv, 0), reachable(nv, 0);
  for (size_t v = 0; v < nv; ++v) {
    const double d = index.distance(mesh.positions[v]);
    near[v] = d < tube;
    reachable[v] = std::isfinite(d);
  }
  TubeCut cut;
  auto remove = [&](const std::array<std::uint32_t, 3>& t) {
    ++removed_triangles;
    cut.removed.push_back(t);
    for (int k = 0; k < 3; ++k)
      cut.removed_edges.insert(
          directed_edge_key(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)]));
  };
  for (const auto& t : mesh.triangles) {
    if (near[t[0]] || near[t[1]] || near[t[2]])
      remove(t);
    else
      cut.kept.push_back(t);
  }
  std::vector<Vec3> free_ends;
  for (std::uint32_t v = 0; v < net.pos.size(); ++v)
    if (net.free_end[v]) free_ends.push_back(net.pos[v]);
  auto near_free_end = [&](const std::array<std::uint32_t, 3>& t) {
    for (const Vec3& q : free_ends)
      for (std::uint32_t v : t)
        if ((mesh.positions[v] - q).norm() < kFreeEndReach * tube) return true;
    return false;
  };
  // Only triangles with a corner within the index's reach of a curve can be on the cut.
  std::vector<size_t> candidates;
  for (size_t i = 0; i < cut.kept.size(); ++i)
    if (std::any_of(cut.kept[i].begin(), cut.kept[i].end(),
                    [&](std::uint32_t v) { return reachable[v]; }))
      candidates.push_back(i);
  std::vector<std::uint8_t> tip(cut.kept.size(), 0);
  for (int pass = 0; pass < 16; ++pass) {
    std::vector<size_t> tips;
    for (size_t i : candidates) {
      if (tip[i]) continue;
      const auto& t = cut.kept[i];
      int on_rim = 0;
      for (int k = 0; k < 3; ++k)
        on_rim += cut.removed_edges.count(directed_edge_key(t[static_cast<size_t>((k + 1) % 3)],
                                                            t[static_cast<size_t>(k)])) > 0;
      if (on_rim >= 2 && !near_free_end(t)) tips.push_back(i);
    }
    if (tips.empty()) break;
    for (size_t i : tips) {
      tip[i] = 1;
      remove(cut.kept[i]);
    }
  }
  size_t w = 0;
  for (size_t i = 0; i < cut.kept.size(); ++i)
    if (!tip[i]) cut.kept[w++] = cut.kept[i];
  cut.kept.resize(w);
  return cut;
}

// Where a chain of the rim cannot be joined, the tube's triangles within `radius` of the place
// are put back: that neighbourhood stays as marching cubes made it, its sheets rounded off,
// and the rim now runs around it (crossing the curve on the restored triangles, where it
// turns back as around a fold). Returns the triangles put back.
long long restore_near(TubeCut& cut, const Mesh& mesh, const Vec3& place, double radius) {
  long long restored = 0;
  size_t w = 0;
  for (size_t i = 0; i < cut.removed.size(); ++i) {
    const auto& t = cut.removed[i];
    const bool near = std::any_of(t.begin(), t.end(), [&](std::uint32_t v) {
      return (mesh.positions[v] - place).norm() < radius;
    });
    if (!near) {
      cut.removed[w++] = t;
      continue;
    }
    for (int k = 0; k < 3; ++k)
      cut.removed_edges.erase(
          directed_edge_key(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)]));
    cut.kept.push_back(t);
    ++restored;
  }
  cut.removed.resize(w);
  return restored;
}

// The network's vertices join the mesh (their indices are base + graph vertex).
void append_network_vertices(Mesh& mesh, const Network& net, const Surface& surface) {
  const size_t base = mesh.positions.size();
  mesh.positions.insert(mesh.positions.end(), net.pos.begin(), net.pos.end());
  if (mesh.is_boundary.size() != base) mesh.is_boundary.assign(base, 0);
  for (const Vec3& p : net.pos)
    mesh.is_boundary.push_back(!surface.clip.is_empty_spec() &&
                               std::abs(surface.clip.value(p)) <= 1e-9 * surface.scene_radius());
}

// The join's result goes into the mesh: the kept triangles, the strips and the network's
// vertices; then the strips are refined.
void finish_join(Mesh& mesh, const Surface& surface, const Network& net, TubeCut cut,
                 std::vector<std::array<std::uint32_t, 3>> added, double mean_edge,
                 const CrossingOptions& options, CrossingStats& stats) {
  const std::uint32_t base = static_cast<std::uint32_t>(mesh.positions.size());
  mesh.triangles = std::move(cut.kept);
  const size_t first_added = mesh.triangles.size();
  mesh.triangles.insert(mesh.triangles.end(), added.begin(), added.end());
  append_network_vertices(mesh, net, surface);
  std::unordered_set<std::uint64_t> curve_edges;
  for (const auto& c : net.curves)
    for (size_t i = 0; i + 1 < c.verts.size(); ++i)
      curve_edges.insert(edge_key(c.verts[i] + base, c.verts[i + 1] + base));
  stats.strip_vertices =
      refine_strips(mesh, first_added, options.split_edges * mean_edge, surface, curve_edges);
  stats.added_triangles = static_cast<long long>(mesh.triangles.size() - first_added);
}

// Sheets meet on the crossing curves: the tube around them is cut out and its rim joined to
// the curves, then the joining strips are refined. A place where the rim cannot be joined is
// put back as marching cubes made it (restore_near), and the join is tried again: the first
// time within kRestoreTubes tube radii of the place, each further failure there doubles the
// radius. Returns false (with stats.failure; the mesh untouched) only when failures remain
// after kRestoreRounds rounds.
constexpr double kRestoreTubes = 3;
constexpr int kRestoreRounds = 24;

bool join_sheets_on_curves(Mesh& mesh, const Surface& surface, const Network& net, double cell_size,
                           double mean_edge, const CrossingOptions& options, CrossingStats& stats) {
  const double tube = options.tube_cells * cell_size;
  const CrossingCurves crossing = crossing_curves_of(net);
  // A rim vertex is within a tube's radius plus an edge of the curve, well inside the reach.
  const SingularSetIndex index(crossing.set, 3 * tube);
  TubeCut cut = cut_tube(mesh, net, index, tube, stats.removed_triangles);
  std::vector<std::array<std::uint32_t, 3>> added;
  for (int round = 0;; ++round) {
    std::vector<detail::JoinFailure> failures;
    added = detail::join_rim(mesh, surface, cut, net, index, crossing, tube, failures);
    if (failures.empty()) break;
    if (round == kRestoreRounds) {
      stats.failure = failures.front().what;
      stats.removed_triangles = 0;
      stats.left_as_marching_cubes.clear();
      return false;
    }
    // A failure at a place put back in an earlier round doubles that place's radius (once a
    // round); any other starts a place of its own.
    auto& places = stats.left_as_marching_cubes;
    const size_t earlier = places.size();
    std::vector<std::uint8_t> grown(earlier, 0);
    for (const detail::JoinFailure& f : failures) {
      size_t k = 0;
      while (k < places.size() && !((places[k].at - f.where).norm() < places[k].radius + tube)) ++k;
      if (k == places.size()) {
        places.push_back({f.where, kRestoreTubes * tube});
      } else if (k < earlier && !grown[k]) {
        grown[k] = 1;
        places[k].radius *= 2;
      } else {
        continue;
      }
      stats.removed_triangles -= restore_near(cut, mesh, places[k].at, places[k].radius);
    }
  }
  finish_join(mesh, surface, net, std::move(cut), std::move(added), mean_edge, options, stats);
  return true;
}

}  // namespace

CrossingStats mesh_crossings(Mesh& mesh, const Surface& surface, double cell_size,
                             const CrossingOptions& options, SingularSet* set_out,
                             std::stop_token stop) {
  const auto t0 = std::chrono::steady_clock::now();
  CrossingStats stats;
  if (mesh.triangles.empty() || !(cell_size > 0)) return stats;
  const double mean_edge = mean_edge_length(mesh);
  const double spacing = options.spacing_edges * mean_edge;

  SingularSetOptions so;
  so.cells = options.search_cells > 0
                 ? options.search_cells
                 : std::clamp(static_cast<int>(surface.bounds().size().maxCoeff() / cell_size / 2),
                              48, 96);
  so.spacing = spacing;
  SingularSet set = find_singular_set(surface, so, stop);
  if (set_out) *set_out = set;
  auto finish = [&] {
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return stats;
  };
  if (stop.stop_requested() || set.has_singular_sheet) return finish();

  Network net = build_network(set, spacing, options.isolated_curves);
  for (const auto& c : net.curves)
    (c.kind == CurveKind::kCrossing ? stats.crossing_curves : stats.isolated_curves)++;
  if (net.curves.empty()) return finish();

  const std::uint32_t base = static_cast<std::uint32_t>(mesh.positions.size());
  bool crossings = true;
  if (stats.crossing_curves > 0) {
    crossings = join_sheets_on_curves(mesh, surface, net, cell_size, mean_edge, options, stats);
    if (!crossings && stats.isolated_curves == 0) return finish();  // the mesh is untouched
  }
  // The curves' vertices join the mesh (if the join did not already add them); a failed join
  // keeps only the isolated curves.
  if (mesh.positions.size() == base) append_network_vertices(mesh, net, surface);
  if (!mesh.normals.empty()) mesh.normals.resize(mesh.positions.size(), Vec3::Zero());
  for (const auto& c : net.curves) {
    if (c.kind == CurveKind::kCrossing && !crossings) continue;
    MeshCurve mc;
    mc.kind = c.kind;
    mc.closed = c.closed;
    for (std::uint32_t v : c.verts) mc.vertices.push_back(base + v);
    mesh.curves.push_back(std::move(mc));
  }
  remove_unreferenced_vertices(mesh);
  stats.curve_vertices = static_cast<long long>(net.pos.size());
  if (!mesh.normals.empty()) compute_field_normals(mesh, surface);
  return finish();
}

}  // namespace zeroset
