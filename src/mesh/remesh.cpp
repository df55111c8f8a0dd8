// Isotropic remeshing with locked features (include/zeroset/mesh/remesh.h, docs/meshing.md):
// set-up, the topology passes and the driver. Relaxation and projection: remesh_relax.cpp.
#include "zeroset/mesh/remesh.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>

#include <fmt/core.h>

#include "remesh_detail.h"
#include "zeroset/error.h"
#include "zeroset/mesh/mesh_ops.h"
#include "zeroset/surface/analysis.h"
#include "zeroset/surface/singular_set.h"

namespace zeroset::detail {

void Remesher::setup() {
  const size_t nv = mesh.positions.size();
  for (const Tri& t : mesh.triangles)
    for (std::uint32_t v : t)
      if (v >= nv) throw InvalidArgument("mesh", fmt::format("vertex {}", v), "does not exist");
  if (mesh.is_boundary.size() != nv) mesh.is_boundary.assign(nv, 0);
  kind.assign(nv, kFree);
  on_curve.assign(nv, 0);
  pinch_held.assign(nv, 0);
  alive_vertex.assign(nv, 1);
  alive_tri.assign(mesh.triangles.size(), 1);
  vt.assign(nv, {});
  grad_at.assign(nv, Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
  grad.assign(nv, Vec3::Zero());
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    for (std::uint32_t v : mesh.triangles[t]) vt[v].push_back(t);
  for (size_t v = 0; v < nv; ++v) {
    if (!mesh.is_boundary[v]) continue;
    const Vec3& p = mesh.positions[v];
    const bool on_clip =
        !surface.clip.is_empty_spec() && std::abs(surface.clip.value(p)) <= 1e-7 * (1 + p.norm());
    kind[v] = opt.boundary == BoundaryMode::kConstrained && on_clip ? kClip : kLocked;
  }
  for (const MeshCurve& c : mesh.curves) {
    for (std::uint32_t v : c.vertices) kind[v] = kLocked, on_curve[v] = 1;
    for (size_t k = 1; k < c.vertices.size(); ++k)
      curve_edges.insert(edge_key(c.vertices[k - 1], c.vertices[k]));
  }
  // Open border edges that are not on the clip, and edges of three or more triangles, hold
  // their vertices.
  double sum = 0;
  long long count = 0;
  for (std::uint32_t v = 0; v < nv; ++v)
    for (std::uint32_t t : vt[v])
      for (std::uint32_t w : mesh.triangles[t]) {
        if (w <= v) continue;
        std::uint32_t et[2];
        const int n = edge_tris(v, w, et);
        // Each edge is met once per triangle on it: count it at its first triangle.
        if (et[0] != t) continue;
        sum += (mesh.positions[v] - mesh.positions[w]).norm(), ++count;
        if (n == 2) continue;
        if (n == 1 && kind[v] == kClip && kind[w] == kClip) continue;
        if (n > 2) curve_edges.insert(edge_key(v, w)), on_curve[v] = on_curve[w] = 1;
        for (std::uint32_t u : {v, w})
          if (kind[u] == kFree || n > 2) kind[u] = kLocked;
      }
  const double mean = count > 0 ? sum / static_cast<double>(count) : 0.0;
  L = opt.target_edge > 0 ? opt.target_edge : mean;
  lo = 0.8 * L, hi = hi_collapse = 4.0 / 3.0 * L;
  // A triangle must keep at least this much (twice its area): far below any a remesh makes.
  min_area = 1e-4 * L * L;
  stats.target_edge = L;
}

// The nearest vertex goes exactly onto each isolated singular point and stays there.
void Remesher::find_singular_points(const SingularSet& set) {
  if (!opt.find_singular_points || !surface.clip.is_bounded()) return;
  // The surface's own exact points first (the catalog's nodes), then those found.
  for (const Vec3& q : surface.singular_points())
    if (surface.clip.contains(q)) pending.push_back(q);
  for (const SingularPoint& sp : set.points) {
    if (sp.kind == SingularPointKind::kClipEnd) continue;
    if (std::none_of(pending.begin(), pending.end(),
                     [&](const Vec3& q) { return (q - sp.position).norm() < 1e-6 * L; }))
      pending.push_back(sp.position);
  }
}

void Remesher::hold_pending_points() {
  std::vector<Vec3> left;
  std::vector<std::pair<double, std::uint32_t>> near;
  std::vector<Vec3> before;
  for (const Vec3& q : pending) {
    near.clear();
    for (std::uint32_t v = 0; v < mesh.positions.size(); ++v) {
      if (!alive_vertex[v] || vt[v].empty()) continue;
      const double d = (mesh.positions[v] - q).norm();
      if (d <= 2 * L) near.emplace_back(d, v);
    }
    std::sort(near.begin(), near.end());
    // A vertex there already (on a singular curve, say): it holds the point.
    if (!near.empty() &&
        (near[0].first == 0 || (on_curve[near[0].second] && near[0].first < 1e-9 * L))) {
      kind[near[0].second] = kLocked, on_curve[near[0].second] = 1;
      rings_stale = true;  // the border chains may end there now
      stats.singular_points.push_back(mesh.positions[near[0].second]);
      continue;
    }
    // Else the nearest free vertex that can move there without turning a triangle over.
    bool held = false;
    for (const auto& [d, v] : near) {
      if (kind[v] != kFree || pinch_held[v]) continue;  // a curve, border or held vertex
      const Vec3 old = mesh.positions[v];
      before.clear();
      for (std::uint32_t t : vt[v]) before.push_back(normal(mesh.triangles[t]));
      mesh.positions[v] = q;
      bool ok = true;
      for (size_t k = 0; k < vt[v].size() && ok; ++k) {
        const Vec3 n = normal(mesh.triangles[vt[v][k]]);
        ok = n.norm() > min_area && n.dot(before[k]) > 0;
      }
      if (!ok) {
        mesh.positions[v] = old;
        continue;
      }
      kind[v] = kLocked, on_curve[v] = 1;
      rings_stale = true;
      stats.singular_points.push_back(q);
      held = true;
      break;
    }
    if (!held) left.push_back(q);
  }
  pending.swap(left);
}

std::vector<std::array<std::uint32_t, 2>> Remesher::edges_where(bool longer) const {
  // As edge keys (smaller vertex in the high half): sorted as numbers, they come in the order
  // of their vertex pairs, and a sort of numbers is much faster than one of pairs.
  std::vector<std::uint64_t> keys;
  const double hi2 = hi * hi, lo2 = lo * lo;  // squared lengths: no square roots
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!alive_tri[t]) continue;
    const Tri& tr = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = tr[k], b = tr[(k + 1) % 3];
      const double len2 = (mesh.positions[a] - mesh.positions[b]).squaredNorm();
      if (longer ? len2 > hi2 : len2 < lo2) keys.push_back(edge_key(a, b));
    }
  }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<std::array<std::uint32_t, 2>> out(keys.size());
  for (size_t i = 0; i < keys.size(); ++i)
    out[i] = {static_cast<std::uint32_t>(keys[i] >> 32), static_cast<std::uint32_t>(keys[i])};
  return out;
}

std::uint32_t Remesher::add_vertex(const Vec3& p, Kind k) {
  mesh.positions.push_back(p);
  mesh.is_boundary.push_back(k == kClip);
  kind.push_back(k);
  on_curve.push_back(0);
  pinch_held.push_back(0);
  alive_vertex.push_back(1);
  vt.emplace_back();
  grad_at.push_back(Vec3::Constant(std::numeric_limits<double>::quiet_NaN()));
  grad.emplace_back(Vec3::Zero());
  return static_cast<std::uint32_t>(mesh.positions.size() - 1);
}

std::uint32_t Remesher::add_triangle(const Tri& t) {
  mesh.triangles.push_back(t);
  alive_tri.push_back(1);
  const auto id = static_cast<std::uint32_t>(mesh.triangles.size() - 1);
  for (std::uint32_t v : t) vt[v].push_back(id);
  rings_stale = true;
  return id;
}

void Remesher::drop_from(std::uint32_t v, std::uint32_t t) {
  rings_stale = true;
  auto& l = vt[v];
  l.erase(std::remove(l.begin(), l.end(), t), l.end());
}

namespace {

// The Morton code of a cell: the bits of x, y and z (21 each) interleaved.
std::uint64_t morton(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  auto spread = [](std::uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  };
  return spread(x) | spread(y) << 1 | spread(z) << 2;
}

}  // namespace

void Remesher::renumber() {
  const size_t nv = mesh.positions.size();
  std::vector<std::uint8_t> used(nv, 0);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    if (alive_tri[t])
      for (std::uint32_t v : mesh.triangles[t]) used[v] = 1;
  for (const MeshCurve& c : mesh.curves)
    for (std::uint32_t v : c.vertices) used[v] = 1;
  Vec3 lo_corner = Vec3::Constant(std::numeric_limits<double>::infinity());
  for (size_t v = 0; v < nv; ++v)
    if (used[v]) lo_corner = lo_corner.cwiseMin(mesh.positions[v]);
  // Cells of about an edge: finer would not help, coarser would mix far vertices.
  const double cell = L > 0 ? L : 1.0;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order;
  for (std::uint32_t v = 0; v < nv; ++v) {
    if (!used[v]) continue;
    const Vec3 c = ((mesh.positions[v] - lo_corner) / cell).array().floor();
    auto q = [](double x) { return static_cast<std::uint32_t>(std::clamp(x, 0.0, 2097151.0)); };
    order.emplace_back(morton(q(c.x()), q(c.y()), q(c.z())), v);
  }
  std::sort(order.begin(), order.end());
  std::vector<std::uint32_t> remap(nv, kNone);
  for (std::uint32_t i = 0; i < order.size(); ++i) remap[order[i].second] = i;
  auto permute = [&](auto& a) {
    std::remove_reference_t<decltype(a)> b(order.size());
    for (size_t i = 0; i < order.size(); ++i) b[i] = std::move(a[order[i].second]);
    a.swap(b);
  };
  permute(mesh.positions);
  permute(mesh.is_boundary);
  if (mesh.normals.size() == nv) permute(mesh.normals);
  permute(kind), permute(on_curve), permute(pinch_held), permute(grad_at), permute(grad);
  alive_vertex.assign(order.size(), 1);
  std::vector<Tri> tris;
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    if (alive_tri[t]) {
      Tri tr = mesh.triangles[t];
      for (auto& v : tr) v = remap[v];
      tris.push_back(tr);
    }
  std::sort(tris.begin(), tris.end(), [](const Tri& a, const Tri& b) {
    return std::min({a[0], a[1], a[2]}) < std::min({b[0], b[1], b[2]});
  });
  mesh.triangles.swap(tris);
  alive_tri.assign(mesh.triangles.size(), 1);
  vt.assign(order.size(), {});
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
    for (std::uint32_t v : mesh.triangles[t]) vt[v].push_back(t);
  for (MeshCurve& c : mesh.curves)
    for (auto& v : c.vertices) v = remap[v];
  std::unordered_set<std::uint64_t> edges;
  for (std::uint64_t e : curve_edges)
    edges.insert(edge_key(remap[static_cast<std::uint32_t>(e >> 32)],
                          remap[static_cast<std::uint32_t>(e & 0xffffffffu)]));
  curve_edges.swap(edges);
  rings_stale = true;
}

long long Remesher::split_pass() {
  long long n = 0;
  for (const auto& [a, b] : edges_where(true)) {
    const double len = (mesh.positions[a] - mesh.positions[b]).norm();
    if (!(len > hi) || curve_edges.count(edge_key(a, b))) continue;
    std::uint32_t et[2];
    const int ne = edge_tris(a, b, et);
    if (ne == 0 || ne > 2) continue;
    const bool border = ne == 1;
    if (border && !(kind[a] == kClip && kind[b] == kClip)) continue;
    const Vec3 mid = 0.5 * (mesh.positions[a] + mesh.positions[b]);
    // A new vertex goes onto F = 0 (the clip curve on the border) or the edge stays.
    Vec3 p = mid;
    if (!project(border, p, 0.5 * len)) continue;
    const std::uint32_t m = add_vertex(p, border ? kClip : kFree);
    ev().value_gradient(p, grad[m]);  // for agrees_with_gradient, as every other vertex has
    grad_at[m] = p;
    // Each triangle (a, b, c) → (a, m, c), (m, b, c) in its own orientation.
    std::vector<Vec3> old_normals;
    std::vector<std::uint32_t> made;
    for (int k = 0; k < ne; ++k) {
      const std::uint32_t t = et[k];
      const Tri tr = mesh.triangles[t];
      old_normals.push_back(normal(tr));
      int i = 0;
      while (!(tr[i] != a && tr[i] != b)) ++i;
      const std::uint32_t c = tr[i], x = tr[(i + 1) % 3], y = tr[(i + 2) % 3];  // c → x → y
      alive_tri[t] = 0;
      for (std::uint32_t v : tr) drop_from(v, t);
      made.push_back(add_triangle({c, x, m}));
      made.push_back(add_triangle({c, m, y}));
    }
    // The projected vertex may not turn a triangle over: fall back to the midpoint.
    auto bad = [&] {
      for (size_t k = 0; k < made.size(); ++k) {
        const Vec3 nn = normal(mesh.triangles[made[k]]);
        if (!(nn.norm() > min_area && nn.dot(old_normals[k / 2]) > 0)) return true;
        if (agrees_with_gradient(old_normals[k / 2], mesh.triangles[et[k / 2]]) &&
            !agrees_with_gradient(nn, mesh.triangles[made[k]]))
          return true;
      }
      return false;
    };
    if (bad()) {
      // Turned over: undo (the new vertex stays, unused, and is dropped at the end).
      for (std::uint32_t t : made) {
        alive_tri[t] = 0;
        for (std::uint32_t v : mesh.triangles[t]) drop_from(v, t);
      }
      for (int k = 0; k < ne; ++k) {
        alive_tri[et[k]] = 1;
        for (std::uint32_t v : mesh.triangles[et[k]]) vt[v].push_back(et[k]);
      }
      alive_vertex[m] = 0;
      continue;
    }
    ++n;
  }
  return n;
}

// Collapses v into w (w stays where it is). Returns false, changing nothing, when refused.
bool Remesher::try_collapse(std::uint32_t v, std::uint32_t w, std::vector<std::uint32_t>& nv,
                            std::vector<std::uint32_t>& nw) {
  if (kind[v] == kLocked || pinch_held[v]) return false;
  // The cheap tests first: no edge longer than hi_collapse (most refusals, so before anything
  // else is looked up), the triangles on the edge, then the link condition (the common
  // neighbours are exactly the opposite corners).
  const Vec3& pw = mesh.positions[w];
  const double hi2 = hi_collapse * hi_collapse;
  for (std::uint32_t t : vt[v])
    for (std::uint32_t x : mesh.triangles[t])
      if (x != v && x != w && (mesh.positions[x] - pw).squaredNorm() > hi2) return false;
  std::uint32_t et[2];
  const int ne = edge_tris(v, w, et);
  if (ne == 0 || ne > 2) return false;
  if (kind[v] == kClip && !(kind[w] == kClip && ne == 1)) return false;
  if (kind[v] == kFree && ne != 2) return false;
  neighbours(v, nv);
  neighbours(w, nw);
  std::vector<std::uint32_t> common;
  std::set_intersection(nv.begin(), nv.end(), nw.begin(), nw.end(), std::back_inserter(common));
  if (static_cast<int>(common.size()) != ne) return false;
  for (std::uint32_t t : vt[v]) {
    const Tri& tr = mesh.triangles[t];
    if (tr[0] == w || tr[1] == w || tr[2] == w) continue;
    Tri nt = tr;
    for (auto& u : nt)
      if (u == v) u = w;
    const Vec3 before = normal(tr), after = normal(nt);
    // Not turned, not folded by more than 60°, not (nearly) flat, not turned against ∇F.
    if (!(after.norm() > min_area && after.dot(before) > 0.5 * after.norm() * before.norm()))
      return false;
    if (!agrees_with_gradient(after, nt) && agrees_with_gradient(before, tr)) return false;
  }
  // Apply.
  for (int k = 0; k < ne; ++k) {
    alive_tri[et[k]] = 0;
    for (std::uint32_t u : mesh.triangles[et[k]]) drop_from(u, et[k]);
  }
  for (std::uint32_t t : vt[v]) {
    for (auto& u : mesh.triangles[t])
      if (u == v) u = w;
    vt[w].push_back(t);
  }
  vt[v].clear();
  alive_vertex[v] = 0;
  return true;
}

long long Remesher::collapse_pass() {
  long long n = 0;
  std::vector<std::uint32_t> nv, nw;
  for (const auto& [a, b] : edges_where(false)) {
    if (!alive_vertex[a] || !alive_vertex[b]) continue;
    if ((mesh.positions[a] - mesh.positions[b]).norm() >= lo) continue;
    if (on_curve[a] && on_curve[b] && curve_edges.count(edge_key(a, b))) continue;
    if (try_collapse(a, b, nv, nw) || try_collapse(b, a, nv, nw))
      ++n;
    else
      ++stats.refused_collapses;
  }
  return n;
}

// Flips edge (a, b) of triangles t1 = (a, b, c), t2 = (b, a, d) into (a, d, c), (d, b, c)
// when `wanted` says so and the geometry allows it; `may_want(a, b, c)` rules edges out
// before the other triangle is looked up.
template <class MayWant, class Wanted>
long long Remesher::flip_pass(MayWant may_want, Wanted wanted) {
  long long n = 0;
  for (std::uint32_t t1 = 0; t1 < mesh.triangles.size(); ++t1) {
    for (int k = 0; k < 3 && alive_tri[t1]; ++k) {
      const Tri tr = mesh.triangles[t1];
      const std::uint32_t a = tr[k], b = tr[(k + 1) % 3], c = tr[(k + 2) % 3];
      if (!may_want(a, b, c)) continue;
      // A curve edge has both ends on a curve: the hash lookup only then.
      if (on_curve[a] && on_curve[b] && curve_edges.count(edge_key(a, b))) continue;
      std::uint32_t et[2];
      if (edge_tris(a, b, et) != 2) continue;
      const std::uint32_t t2 = et[0] == t1 ? et[1] : et[0];
      const Tri& o = mesh.triangles[t2];
      std::uint32_t d = kNone;
      for (int i = 0; i < 3; ++i)
        if (o[i] == b && o[(i + 1) % 3] == a) d = o[(i + 2) % 3];
      if (d == kNone || d == c) continue;  // misoriented pair, or a doubled triangle
      if (!wanted(a, b, c, d)) continue;   // first: the cheapest test that rules most out
      std::uint32_t cd[2];
      if (edge_tris(c, d, cd) != 0) continue;
      const auto& p = mesh.positions;
      const Tri n1{a, d, c}, n2{d, b, c};
      const Vec3 o1 = normal(tr), o2 = normal(o), m1 = normal(n1), m2 = normal(n2);
      const Vec3 sum = o1 + o2;
      if (!(m1.norm() > min_area && m2.norm() > min_area)) continue;
      if (!(m1.dot(sum) > 0.5 * m1.norm() * sum.norm() &&
            m2.dot(sum) > 0.5 * m2.norm() * sum.norm()))
        continue;
      if (!(agrees_with_gradient(m1, n1) && agrees_with_gradient(m2, n2)) &&
          agrees_with_gradient(o1, tr) && agrees_with_gradient(o2, o))
        continue;
      // Never much worse angles than before.
      const double before = std::min(min_angle(p[a], p[b], p[c]), min_angle(p[b], p[a], p[d]));
      const double after = std::min(min_angle(p[a], p[d], p[c]), min_angle(p[d], p[b], p[c]));
      if (after < 0.5 * before) continue;
      drop_from(a, t2), drop_from(b, t1);
      mesh.triangles[t1] = n1, mesh.triangles[t2] = n2;
      vt[d].push_back(t1), vt[c].push_back(t2);
      if (!valence.empty()) --valence[a], --valence[b], ++valence[c], ++valence[d];
      ++n;
    }
  }
  return n;
}

long long Remesher::valence_flips() {
  // Targets and valences once per pass (flip_pass keeps the valences up to date).
  const size_t n = mesh.positions.size();
  std::vector<int> target(n, kAnyValence);
  valence.assign(n, 0);
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!alive_vertex[v] || vt[v].empty()) continue;
    target[v] = valence_target(v);
    // A disc has as many neighbours as triangles, half a disc one more.
    if (target[v] != kAnyValence)
      valence[v] = static_cast<int>(vt[v].size()) + (target[v] == 4 ? 1 : 0);
  }
  // How much nearer (negative) or farther (positive) from their targets the flip takes a,
  // b and c; d's share is at least -1.
  auto change = [&](const std::uint32_t* vs, int count) {
    int sum = 0;
    const int delta[4] = {-1, -1, 1, 1};
    for (int i = 0; i < count; ++i)
      if (target[vs[i]] != kAnyValence)
        sum += std::abs(valence[vs[i]] + delta[i] - target[vs[i]]) -
               std::abs(valence[vs[i]] - target[vs[i]]);
    return sum;
  };
  const long long flips = flip_pass(
      [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
        const std::uint32_t vs[3] = {a, b, c};
        return change(vs, 3) <= 0;
      },
      [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
        const std::uint32_t vs[4] = {a, b, c, d};
        // A vertex may not drop below three neighbours.
        return change(vs, 4) < 0 && valence[a] > 3 && valence[b] > 3;
      });
  valence.clear();
  return flips;
}

long long Remesher::delaunay_flips() {
  const auto& p = mesh.positions;
  // The two angles facing the edge add up to more than π (with a margin against cycling), so
  // one of them is obtuse: each edge is tested from the triangle whose angle facing it is (the
  // other triangle's turn comes too), before the other triangle is looked up.
  return flip_pass([&](std::uint32_t a, std::uint32_t b,
                       std::uint32_t c) { return (p[a] - p[c]).dot(p[b] - p[c]) < 0; },
                   [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
                     return corner_angle(p[c], p[a], p[b]) + corner_angle(p[d], p[a], p[b]) >
                            M_PI + 1e-3;
                   });
}

}  // namespace zeroset::detail

namespace zeroset {
namespace {

using Clock = std::chrono::steady_clock;
using detail::kBandGrowth;
using detail::kFixedBandIterations;
using detail::kFlipOnlyRounds;
using detail::kMaxSettleSteps;
using detail::Remesher;

void check_options(const RemeshOptions& o) {
  auto bad = [](const char* name, double v, const char* why) {
    throw InvalidArgument(name, fmt::format("{}", v), why);
  };
  if (!(o.target_edge >= 0 && std::isfinite(o.target_edge)))
    bad("target_edge", o.target_edge, "must be ≥ 0 (0: the mean edge length)");
  if (o.max_iterations < 0) bad("max_iterations", o.max_iterations, "must be ≥ 0");
  if (o.relax_steps < 0) bad("relax_steps", o.relax_steps, "must be ≥ 0");
  if (o.polish_rounds < 0) bad("polish_rounds", o.polish_rounds, "must be ≥ 0");
  if (!(o.rest_move > 0)) bad("rest_move", o.rest_move, "must be > 0");
  if (o.threads < 0) bad("threads", o.threads, "must be ≥ 0");
}

}  // namespace

RemeshStats remesh(Mesh& mesh, const Surface& surface, const RemeshOptions& options,
                   std::stop_token stop) {
  check_options(options);
  const auto t0 = Clock::now();
  Remesher r(mesh, surface, options);
  r.setup();
  if (mesh.triangles.empty() || !(r.L > 0)) {
    r.stats.converged = true;
    return r.stats;
  }
  SingularSet found;
  if (options.find_singular_points && surface.clip.is_bounded() && !options.singular_set)
    found = find_singular_set(surface);
  const SingularSet& set =
      options.find_singular_points && options.singular_set ? *options.singular_set : found;
  std::vector<Vec3> pinches;
  for (const SingularPoint& sp : set.points)
    if (sp.kind == SingularPointKind::kPinch) pinches.push_back(sp.position);
  const detail::PinchStep pinch =
      detail::improve_near_pinch_points(mesh, surface, pinches, r.L, options, stop);
  if (pinch.improved) {
    r.setup();  // the triangles near the pinch points have changed
    for (std::uint32_t v : pinch.held) r.pinch_held[v] = 1;
    r.stats.pinch_held_vertices = static_cast<long long>(pinch.held.size());
  }
  r.stats.pinch_improver_steps = pinch.steps;
  r.find_singular_points(set);
  r.hold_pending_points();
  {
    // ∇F at every vertex before the first topology pass, for agrees_with_gradient.
    std::vector<std::uint32_t> all(mesh.positions.size());
    std::iota(all.begin(), all.end(), 0u);
    r.update_gradients(all);
  }
  RemeshStats& st = r.stats;
  // Splits and collapses can undo each other where relaxation stretches an edge across a
  // threshold and back, so after two iterations the band [lo, hi] widens by a tenth at each
  // iteration: the mesh comes to rest with every edge within the band reached.
  bool topology_at_rest = false;
  for (int it = 0; it < options.max_iterations && !stop.stop_requested(); ++it) {
    const double widen = 1 + kBandGrowth * std::max(0, it - kFixedBandIterations);
    r.hi = 4.0 / 3.0 * r.L * widen, r.lo = 0.8 * r.L / widen;
    const long long splits = r.split_pass();
    const long long collapses = r.collapse_pass();
    const long long flips = r.valence_flips();
    // The first passes append a vertex at every split and leave holes at every collapse:
    // numbered again along a space-filling curve, neighbours are near each other in memory,
    // which makes every relaxation step 16 to 20% faster (docs/meshing.md). A
    // small mesh fits in the cache and keeps its order.
    if (it == 0 && mesh.positions.size() >= detail::kRenumberVertices) r.renumber();
    double moved = 0;
    for (int k = 0; k < options.relax_steps; ++k) moved = std::max(moved, r.relax());
    st.splits += splits, st.collapses += collapses, st.flips += flips;
    st.iterations = it + 1;
    st.last_max_move = moved;
    // A point no vertex could take yet: the mesh around it has changed, try again.
    if (!r.pending.empty()) r.hold_pending_points();
    if (splits + collapses + flips == 0) {
      topology_at_rest = true;
      break;
    }
  }
  // Polish: Delaunay flips between nearly coplanar triangles, relaxing in between, until no
  // flip applies. Where relaxation and flips keep trading places (a grid of squares, whose
  // diagonals are all cocircular; the bent quads next to a pinch point) the last rounds flip
  // without relaxing, which ends: a flip never undoes itself while no vertex moves. Then
  // relaxation until every move is below rest_move, a vertex that still moves that much
  // repeating its step (Remesher::relax).
  bool flips_at_rest = options.polish_rounds == 0;
  const int rounds = flips_at_rest ? 0 : options.polish_rounds + kFlipOnlyRounds;
  for (int k = 0; k < rounds && !stop.stop_requested(); ++k) {
    const long long flips = r.delaunay_flips();
    st.flips += flips;
    if (flips == 0) {
      flips_at_rest = true;
      break;
    }
    if (k < options.polish_rounds)
      for (int j = 0; j < options.relax_steps; ++j) r.relax();
  }
  bool moves_at_rest = false;
  r.step_repeats = detail::kSettleRepeats;
  for (int k = 0; k < kMaxSettleSteps && !stop.stop_requested(); ++k) {
    st.last_max_move = r.relax();
    if (st.last_max_move < options.rest_move) {
      moves_at_rest = true;
      break;
    }
  }
  r.step_repeats = 0;
  st.missed_singular_points = static_cast<long long>(r.pending.size());
  st.converged =
      topology_at_rest && flips_at_rest && moves_at_rest && (!pinch.improved || pinch.converged);
  r.final_projection();
  r.compact();
  r.measure_residual();
  compute_field_normals(mesh, surface, options.threads);
  st.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return st;
}

}  // namespace zeroset
