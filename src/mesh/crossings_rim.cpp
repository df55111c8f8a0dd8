// The join of the cut's rim to the crossing curves: where each rim vertex is anchored on the
// network, and the strips of triangles between the rim and the curves. See docs/meshing.md
// ("Crossings").
#include <fmt/core.h>
#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <unordered_set>

#include "crossings_detail.h"

namespace zeroset::detail {
namespace {

// Where a vertex of the cut's rim is joined: a special vertex, or a place along a curve.
struct Anchor {
  std::uint32_t special = kNone;
  std::uint32_t curve = kNone;
  double arc = 0;
  bool ok() const { return special != kNone || curve != kNone; }
};

// The place on curve c nearest to p, when within `reach` (the plain loop over its segments);
// its distance in `distance`.
Anchor anchor_on_curve(const Network& net, std::uint32_t c, const Vec3& p, double reach,
                       double* distance = nullptr) {
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
  if (distance) *distance = best_d;
  return best;
}

// The point of curve c at arc length `arc`.
Vec3 point_at_arc(const Network& net, const Network::Curve& c, double arc) {
  const auto it = std::upper_bound(c.arc.begin(), c.arc.end(), arc);
  const size_t k = std::clamp<size_t>(static_cast<size_t>(it - c.arc.begin()), 1, c.arc.size() - 1);
  const double len = c.arc[k] - c.arc[k - 1];
  const double t = len > 0 ? std::clamp((arc - c.arc[k - 1]) / len, 0.0, 1.0) : 0.0;
  return (1 - t) * net.pos[c.verts[k - 1]] + t * net.pos[c.verts[k]];
}

// A curve lies on the sheet of a rim vertex at p (unit normal n) when the way to it runs
// within 30° of the sheet's tangent plane. Curves a few cells apart (two sheets crossing a third
// along nearly parallel curves) put a rim vertex near the other sheet's curve: joined there, its
// strip would cross between the sheets.
bool on_own_sheet(const Vec3& p, const Vec3& n, const Vec3& q) {
  const Vec3 d = q - p;
  return n.isZero() || std::abs(d.dot(n)) <= 0.5 * d.norm();
}

// Where a rim vertex at p (unit normal n, or zero) is joined: the nearest place on a crossing
// curve of its own sheet (on_own_sheet; the nearest of all when none is), or the nearest
// special vertex along that curve within `reach`, around which the rim turns.
Anchor anchor_of(const Network& net, const SingularSetIndex& index,
                 const std::vector<std::uint32_t>& curve_of, const Vec3& p, const Vec3& n,
                 double reach) {
  const SingularSetIndex::Nearest hit = index.nearest(p);
  if (hit.curve < 0) return {};
  std::uint32_t c = curve_of[static_cast<size_t>(hit.curve)];
  const std::uint32_t i = hit.segment;
  double arc = net.curves[c].arc[i] + hit.t * (net.curves[c].arc[i + 1] - net.curves[c].arc[i]);
  if (!on_own_sheet(p, n, point_at_arc(net, net.curves[c], arc))) {
    double best_d = std::numeric_limits<double>::infinity();
    for (std::uint32_t other : curve_of) {
      double d = 0;
      const Anchor a = anchor_on_curve(net, other, p, index.reach(), &d);
      if (a.ok() && d < best_d && on_own_sheet(p, n, point_at_arc(net, net.curves[other], a.arc)))
        best_d = d, c = other, arc = a.arc;
    }
  }
  const Network::Curve& curve = net.curves[c];
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

}  // namespace

// Joins the rim of the cut to the crossing curves: each rim edge u → v and the graph path
// between the vertices its ends are joined to bound a polygon (v, u, a_0 … a_k), fanned from u
// over the path's first part and from v over the rest: triangles run like the kept triangle's,
// so each half-sheet keeps its side. Returns the triangles (vertex base + i is graph vertex i);
// the chains that cannot be joined add nothing and are listed in `failures`.
std::vector<std::array<std::uint32_t, 3>> join_rim(const Mesh& mesh, const Surface& surface,
                                                   const TubeCut& cut, const Network& net,
                                                   const SingularSetIndex& index,
                                                   const CrossingCurves& crossing, double reach,
                                                   std::vector<JoinFailure>& failures) {
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
  Evaluator ev(surface.field);
  for (const Chain& ch : rim_chains(rim)) {
    std::vector<Anchor> anchors;
    for (std::uint32_t v : ch.verts) {
      Vec3 g = Vec3::Zero();
      ev.value_gradient(mesh.positions[v], g);
      const Vec3 n = g.allFinite() && g.norm() > 0 ? Vec3(g.normalized()) : Vec3::Zero();
      anchors.push_back(anchor_of(net, index, crossing.curve_of, mesh.positions[v], n, reach));
      if (!anchors.back().ok()) break;
    }
    if (!anchors.back().ok()) {
      const Vec3& p = mesh.positions[ch.verts[anchors.size() - 1]];
      failures.push_back(
          {p, fmt::format("a vertex of the cut at ({:.4g}, {:.4g}, {:.4g}) is far from every "
                          "crossing curve",
                          p.x(), p.y(), p.z())});
      continue;
    }
    std::vector<std::uint32_t> verts = ch.verts;
    std::vector<Vec3> points;
    for (std::uint32_t v : verts) points.push_back(mesh.positions[v]);
    if (ch.closed) start_at_run(verts, points, anchors);
    merge_short_runs(net, points, ch.closed, reach, index.reach(), anchors);
    if (ch.closed) start_at_run(verts, points, anchors);
    const std::vector<std::uint32_t> target = chain_targets(net, anchors, ch.closed, reach);
    const size_t edges = ch.closed ? verts.size() : verts.size() - 1;
    const size_t chain_start = added.size();
    for (size_t e = 0; e < edges; ++e) {
      const size_t j = (e + 1) % verts.size();
      const std::uint32_t u = verts[e], v = verts[j];
      // Two ends of curves on the clip a few tubes apart (a curve that leaves the clip and
      // comes back, or two that end close together): the rim passes from one to the other
      // along the clip, and so does the strip, over the clip between them.
      const bool clip_ends = net.clip_end[target[e]] && net.clip_end[target[j]] &&
                             (net.pos[target[e]] - net.pos[target[j]]).norm() <=
                                 2 * kFreeEndReach * reach;
      if (clip_ends && !graph_path(net, target[e], target[j], 512, path))
        path = {target[e], target[j]};
      else if (!graph_path(net, target[e], target[j], 512, path)) {
        const Vec3& p = mesh.positions[u];
        failures.push_back(
            {p, fmt::format("the cut near ({:.4g}, {:.4g}, {:.4g}) could not be joined to a curve",
                            p.x(), p.y(), p.z())});
        added.resize(chain_start);
        break;
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

}  // namespace zeroset::detail
