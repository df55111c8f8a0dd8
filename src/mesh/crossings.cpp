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

#include "mesh_detail.h"
#include "zeroset/mesh/mesh_ops.h"
#include "zeroset/surface/analysis.h"
#include "zeroset/surface/singular_index.h"

namespace zeroset {
namespace {

using detail::directed_edge_key;
using detail::edge_key;
using detail::kNone;
// A rim that turns back this many tube radii or less before a curve's free end (a pinch
// point) is joined to the end: towards a pinch point the sheets close like a book, and the
// grid loses them a few cells before it.
constexpr double kFreeEndReach = 4.0;

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

// Where a vertex of the cut's rim is joined: a special vertex, or a place along a curve.
struct Anchor {
  std::uint32_t special = kNone;
  std::uint32_t curve = kNone;
  double arc = 0;
  bool ok() const { return special != kNone || curve != kNone; }
};

Anchor anchor_of(const Network& net, const SingularSetIndex& index,
                 const std::vector<std::uint32_t>& curve_of, const Vec3& p, double reach) {
  const SingularSetIndex::Nearest hit = index.nearest(p);
  if (hit.curve < 0) return {};
  const std::uint32_t c = curve_of[static_cast<size_t>(hit.curve)];
  const std::uint32_t i = hit.segment;
  const Network::Curve& curve = net.curves[c];
  const double arc = curve.arc[i] + hit.t * (curve.arc[i + 1] - curve.arc[i]);
  // The nearest special vertex along the curve within `reach` wins: the rim turns around it.
  std::uint32_t best = kNone;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < curve.verts.size(); ++k) {
    const std::uint32_t v = curve.verts[k];
    if (!net.special[v]) continue;
    double d = std::abs(curve.arc[k] - arc);
    if (curve.closed) d = std::min(d, curve.length() - d);
    if (d <= reach && d < best_d) best_d = d, best = v;
  }
  if (best != kNone) return {.special = best};
  return {.curve = c, .arc = arc};
}

// The place on curve c nearest to p, when within `reach` (the plain loop over its segments).
Anchor anchor_on_curve(const Network& net, std::uint32_t c, const Vec3& p, double reach) {
  const Network::Curve& curve = net.curves[c];
  Anchor best;
  double best_d = reach;
  for (size_t i = 0; i + 1 < curve.verts.size(); ++i) {
    const Vec3& a = net.pos[curve.verts[i]];
    const Vec3 ab = net.pos[curve.verts[i + 1]] - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const double d = (a + t * ab - p).norm();
    if (d <= best_d)
      best_d = d, best = {.curve = c, .arc = curve.arc[i] + t * (curve.arc[i + 1] - curve.arc[i])};
  }
  return best;
}

// A closed chain turned to start where a run of anchors on one curve starts (if it has more
// than one run): runs are read from the first vertex on, and one split at the chain's start
// would be joined as two, covering the curve edges between them twice.
void start_at_run(std::vector<std::uint32_t>& verts, std::vector<Vec3>& points,
                  std::vector<Anchor>& anchors) {
  const size_t n = anchors.size();
  auto same = [&](size_t a, size_t b) {
    return anchors[a].special == anchors[b].special &&
           (anchors[a].special != kNone || anchors[a].curve == anchors[b].curve);
  };
  size_t shift = 0;
  while (shift < n && same(shift, (shift + n - 1) % n)) ++shift;
  if (shift == 0 || shift == n) return;
  std::rotate(verts.begin(), verts.begin() + static_cast<long>(shift), verts.end());
  std::rotate(points.begin(), points.begin() + static_cast<long>(shift), points.end());
  std::rotate(anchors.begin(), anchors.begin() + static_cast<long>(shift), anchors.end());
}

// Where a chain passes between two curves that meet (near a triple point, in the sector of a
// sheet between them), a vertex about as close to both can be anchored to the other curve
// than both its neighbours. Its two rim edges would then be joined through the meeting point
// and back, covering the same curve edges twice in opposite directions (a sixth triangle on
// them, one facing against ∇F). Such a short run (at most `short_run` long in arc length,
// with the runs on both sides anchored to one other curve) is anchored to that curve instead.
void merge_short_runs(const Network& net, const std::vector<Vec3>& points, bool closed_chain,
                      double short_run, double reach, std::vector<Anchor>& anchors) {
  const size_t n = anchors.size();
  if (n < 3) return;
  auto curve_at = [&](size_t j) { return anchors[j].special != kNone ? kNone : anchors[j].curve; };
  size_t k = 0;
  while (k < n) {
    const std::uint32_t c = curve_at(k);
    size_t end = k;
    while (end < n && curve_at(end) == c) ++end;
    if (c == kNone || (!closed_chain && (k == 0 || end == n)) || (k == 0 && end == n)) {
      k = end;
      continue;
    }
    const size_t before = (k + n - 1) % n, after = end % n;
    const std::uint32_t other = curve_at(before);
    double lo = anchors[k].arc, hi = lo;
    for (size_t j = k; j < end; ++j)
      lo = std::min(lo, anchors[j].arc), hi = std::max(hi, anchors[j].arc);
    if (other != kNone && other != c && curve_at(after) == other && hi - lo <= short_run) {
      std::vector<Anchor> moved;
      for (size_t j = k; j < end; ++j)
        moved.push_back(anchor_on_curve(net, other, points[j], reach));
      if (std::all_of(moved.begin(), moved.end(), [](const Anchor& a) { return a.ok(); }))
        std::copy(moved.begin(), moved.end(), anchors.begin() + static_cast<long>(k));
    }
    k = end;
  }
}

// The curve vertex nearest to an arc length.
std::uint32_t vertex_at_arc(const Network::Curve& c, double arc) {
  if (c.closed) arc = std::fmod(std::fmod(arc, c.length()) + c.length(), c.length());
  const auto it = std::lower_bound(c.arc.begin(), c.arc.end(), arc);
  size_t k = static_cast<size_t>(it - c.arc.begin());
  if (k >= c.arc.size()) k = c.arc.size() - 1;
  if (k > 0 && arc - c.arc[k - 1] < c.arc[k] - arc) --k;
  return c.verts[k];
}

// Where arc lengths u along a run first turn back: one past the extreme after which they
// return by more than `depth`, having gone that way by more than `depth` from u[0]; u.size()
// if they never do. The rim of a cut zigzags by less than `depth`; a run turns around a fold
// of the sheets near a pinch point, and turns at each end of the curve where one closed rim
// runs along it several times (Plücker's conoid: the rim around its double line goes up and
// down twice, once along each of the four half-sheets).
size_t first_turn(const std::vector<double>& u, double depth) {
  size_t hi = 0, lo = 0;
  int dir = 0;
  for (size_t j = 1; j < u.size(); ++j) {
    if (u[j] > u[hi]) hi = j;
    if (u[j] < u[lo]) lo = j;
    if (dir == 0) dir = u[hi] - u[0] > depth ? 1 : u[0] - u[lo] > depth ? -1 : 0;
    if (dir > 0 && u[hi] - u[j] > depth) return hi + 1;
    if (dir < 0 && u[j] - u[lo] > depth) return lo + 1;
  }
  return u.size();
}

// The vertices of the graph each rim vertex of one chain is joined to. Along a run of rim
// vertices anchored on the same curve the arc length is made monotone in the run's direction,
// so the strip covers each curve edge once (the rim of a cut zigzags a little).
std::vector<std::uint32_t> chain_targets(const Network& net, const std::vector<Anchor>& anchors,
                                         bool closed_chain, double fold_depth) {
  const size_t n = anchors.size();
  std::vector<std::uint32_t> target(n, kNone);
  size_t k = 0;
  while (k < n) {
    if (anchors[k].special != kNone) {
      target[k] = anchors[k].special;
      ++k;
      continue;
    }
    const std::uint32_t c = anchors[k].curve;
    size_t end = k;
    while (end < n && anchors[end].special == kNone && anchors[end].curve == c) ++end;
    const Network::Curve& curve = net.curves[c];
    const double len = curve.length();
    std::vector<double> u(end - k);
    u[0] = anchors[k].arc;
    for (size_t j = k + 1; j < end; ++j) {
      double d = anchors[j].arc - anchors[j - 1].arc;
      if (curve.closed) d -= len * std::round(d / len);
      u[j - k] = u[j - k - 1] + d;
    }
    // A run that goes out and comes back (around a fold of the sheets) is two runs, split
    // where it turns; the rest is read the same way, so a run turning several times is split
    // at every turn.
    const size_t stop = k + first_turn(u, fold_depth);
    const size_t count = stop - k;
    const double free_reach = kFreeEndReach * fold_depth;
    const double dir = u[count - 1] >= u[0] ? 1.0 : -1.0;
    double m = u[0];
    const bool whole_loop = closed_chain && k == 0 && stop == n && curve.closed;
    for (size_t j = k; j < stop; ++j) {
      m = dir > 0 ? std::max(m, u[j - k]) : std::min(m, u[j - k]);
      if (whole_loop) m = dir > 0 ? std::min(m, u[0] + len) : std::max(m, u[0] - len);
      target[j] = vertex_at_arc(curve, m);
    }
    // A run that turns (or ends) near a free end of its curve reaches the end.
    if (!curve.closed)
      for (size_t j : {k, stop - 1}) {
        const double arc = u[j - k];
        if (arc <= free_reach && net.free_end[curve.verts.front()]) target[j] = curve.verts.front();
        if (len - arc <= free_reach && net.free_end[curve.verts.back()])
          target[j] = curve.verts.back();
      }
    k = stop;
  }
  // An open chain starts and ends on the mesh's border (the clip): near a curve's end on the
  // clip it reaches that end, so the sheets meet the curve up to the clip.
  if (!closed_chain && n > 0)
    for (size_t j : {size_t{0}, n - 1}) {
      if (anchors[j].special != kNone) continue;
      const Network::Curve& curve = net.curves[anchors[j].curve];
      if (curve.closed) continue;
      const double arc = anchors[j].arc, reach = kFreeEndReach * fold_depth;
      if (arc <= reach && net.clip_end[curve.verts.front()]) target[j] = curve.verts.front();
      if (curve.length() - arc <= reach && net.clip_end[curve.verts.back()])
        target[j] = curve.verts.back();
    }
  return target;
}

// Shortest path in the graph from a to b (breadth first, at most `limit` vertices visited).
bool graph_path(const Network& net, std::uint32_t a, std::uint32_t b, size_t limit,
                std::vector<std::uint32_t>& path) {
  path.clear();
  if (a == b) {
    path.push_back(a);
    return true;
  }
  std::vector<std::uint32_t> queue{a};
  std::unordered_map<std::uint32_t, std::uint32_t> from{{a, a}};
  for (size_t head = 0; head < queue.size() && queue.size() < limit; ++head) {
    const std::uint32_t x = queue[head];
    for (std::uint32_t y : net.adj[x]) {
      if (from.count(y)) continue;
      from[y] = x;
      if (y == b) {
        for (std::uint32_t z = b; z != a; z = from[z]) path.push_back(z);
        path.push_back(a);
        std::reverse(path.begin(), path.end());
        return true;
      }
      queue.push_back(y);
    }
  }
  return false;
}

// The rim of the cut as chains of directed edges u → v (as they run in their kept triangle).
struct Chain {
  std::vector<std::uint32_t> verts;
  bool closed = false;
};

std::vector<Chain> rim_chains(const std::vector<std::array<std::uint32_t, 2>>& edges) {
  std::unordered_map<std::uint32_t, std::vector<size_t>> out;
  std::unordered_map<std::uint32_t, int> in_count;
  for (size_t e = 0; e < edges.size(); ++e) {
    out[edges[e][0]].push_back(e);
    ++in_count[edges[e][1]];
  }
  std::vector<std::uint8_t> used(edges.size(), 0);
  auto next_edge = [&](std::uint32_t v) -> size_t {
    const auto it = out.find(v);
    if (it == out.end()) return kNone;
    for (size_t e : it->second)
      if (!used[e]) return e;
    return kNone;
  };
  std::vector<Chain> chains;
  auto walk = [&](size_t first) {
    Chain ch;
    ch.verts.push_back(edges[first][0]);
    for (size_t e = first; e != kNone; e = next_edge(edges[e][1])) {
      used[e] = 1;
      if (edges[e][1] == ch.verts.front()) {
        ch.closed = true;
        break;
      }
      ch.verts.push_back(edges[e][1]);
    }
    chains.push_back(std::move(ch));
  };
  // Open chains first (they start on the mesh's border), in edge order for determinism.
  for (size_t e = 0; e < edges.size(); ++e)
    if (!used[e] && in_count[edges[e][0]] == 0) walk(e);
  for (size_t e = 0; e < edges.size(); ++e)
    if (!used[e]) walk(e);
  return chains;
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

// The crossing curves of the network alone, for nearest-segment queries, and the network
// curve each one is.
struct CrossingCurves {
  SingularSet set;
  std::vector<std::uint32_t> curve_of;
};

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

// The mesh with the tube around the crossing curves cut out: the triangles kept and the
// half-edges of those removed.
struct TubeCut {
  std::vector<std::array<std::uint32_t, 3>> kept;
  std::unordered_set<std::uint64_t> removed_edges;
};

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

// Joins the rim of the cut to the crossing curves: each rim edge u → v and the graph path
// between the vertices its ends are joined to bound a polygon (v, u, a_0 … a_k), fanned from u
// over the path's first part and from v over the rest: triangles run like the kept triangle's,
// so each half-sheet keeps its side. Returns the triangles (vertex base + i is graph vertex i),
// or sets `failure`.
std::vector<std::array<std::uint32_t, 3>> join_rim(const Mesh& mesh, const TubeCut& cut,
                                                   const Network& net,
                                                   const SingularSetIndex& index,
                                                   const CrossingCurves& crossing, double reach,
                                                   std::string& failure) {
  const std::uint32_t base = static_cast<std::uint32_t>(mesh.positions.size());
  // The rim: edges of kept triangles whose other triangle was removed.
  std::vector<std::array<std::uint32_t, 2>> rim;
  for (const auto& t : cut.kept)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t u = t[static_cast<size_t>(k)], v = t[static_cast<size_t>((k + 1) % 3)];
      if (cut.removed_edges.count(directed_edge_key(v, u))) rim.push_back({u, v});
    }
  std::vector<std::array<std::uint32_t, 3>> added;
  std::vector<std::uint32_t> path;
  for (const Chain& ch : rim_chains(rim)) {
    std::vector<Anchor> anchors;
    for (std::uint32_t v : ch.verts) {
      anchors.push_back(anchor_of(net, index, crossing.curve_of, mesh.positions[v], reach));
      if (!anchors.back().ok()) {
        failure = fmt::format(
            "a vertex of the cut at ({:.4g}, {:.4g}, {:.4g}) is far from every crossing curve",
            mesh.positions[v].x(), mesh.positions[v].y(), mesh.positions[v].z());
        return {};
      }
    }
    std::vector<std::uint32_t> verts = ch.verts;
    std::vector<Vec3> points;
    for (std::uint32_t v : verts) points.push_back(mesh.positions[v]);
    if (ch.closed) start_at_run(verts, points, anchors);
    merge_short_runs(net, points, ch.closed, reach, index.reach(), anchors);
    if (ch.closed) start_at_run(verts, points, anchors);
    const std::vector<std::uint32_t> target = chain_targets(net, anchors, ch.closed, reach);
    const size_t edges = ch.closed ? verts.size() : verts.size() - 1;
    for (size_t e = 0; e < edges; ++e) {
      const size_t j = (e + 1) % verts.size();
      const std::uint32_t u = verts[e], v = verts[j];
      if (!graph_path(net, target[e], target[j], 512, path)) {
        failure =
            fmt::format("the cut near ({:.4g}, {:.4g}, {:.4g}) could not be joined to a curve",
                        mesh.positions[u].x(), mesh.positions[u].y(), mesh.positions[u].z());
        return {};
      }
      size_t m = 0;  // path[0 .. m] fan from u, path[m .. k] from v
      for (size_t i = 1; i < path.size(); ++i)
        if ((net.pos[path[i]] - mesh.positions[u]).norm() <
            (net.pos[path[i]] - mesh.positions[v]).norm())
          m = i;
      for (size_t i = 0; i < m; ++i) added.push_back({u, base + path[i], base + path[i + 1]});
      added.push_back({u, base + path[m], v});
      for (size_t i = m; i + 1 < path.size(); ++i)
        added.push_back({v, base + path[i], base + path[i + 1]});
    }
  }
  return added;
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

// Sheets meet on the crossing curves: the tube around them is cut out and its rim joined to
// the curves, then the joining strips are refined. Returns false (with stats.failure) when the
// join fails; the mesh is then untouched.
bool join_sheets_on_curves(Mesh& mesh, const Surface& surface, const Network& net, double cell_size,
                           double mean_edge, const CrossingOptions& options, CrossingStats& stats) {
  const double tube = options.tube_cells * cell_size;
  const CrossingCurves crossing = crossing_curves_of(net);
  // A rim vertex is within a tube's radius plus an edge of the curve, well inside the reach.
  const SingularSetIndex index(crossing.set, 3 * tube);
  TubeCut cut = cut_tube(mesh, net, index, tube, stats.removed_triangles);
  const auto added = join_rim(mesh, cut, net, index, crossing, tube, stats.failure);
  if (!stats.failure.empty()) {
    stats.removed_triangles = 0;
    return false;
  }
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
