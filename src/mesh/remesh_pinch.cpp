// The remesher next to pinch points (include/zeroset/mesh/remesh.h, docs/meshing.md,
// "Crossings"): the two sheets through a crossing curve close like a book towards a pinch
// point, a few cells out they are less than an edge apart, and marching cubes has bridged them
// with triangles that face against ∇F. The spring–mass improver's curvature springs pull
// vertices into that fold and turn those triangles; the remesher's centroid relaxation pulls
// vertices across from one sheet to the other instead. So there the springs improve the mesh
// first and the remesher then leaves it alone.
#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "remesh_detail.h"
#include "zeroset/mesh/improve.h"

namespace zeroset::detail {

namespace {

bool within(const Vec3& p, const std::vector<Vec3>& centres, double r) {
  return std::any_of(centres.begin(), centres.end(),
                     [&](const Vec3& c) { return (p - c).squaredNorm() < r * r; });
}

}  // namespace

PinchStep improve_near_pinch_points(Mesh& mesh, const Surface& surface,
                                    const std::vector<Vec3>& pinches, double L,
                                    const RemeshOptions& opt, std::stop_token stop) {
  PinchStep out;
  if (pinches.empty() || !(L > 0)) return out;
  const size_t nv = mesh.positions.size();
  std::vector<std::uint8_t> inside(nv, 0);
  for (size_t v = 0; v < nv; ++v)
    inside[v] = within(mesh.positions[v], pinches, kPinchSpringRadius * L);

  // The triangles with every corner inside, and their vertices renumbered.
  std::vector<std::uint32_t> tris, sub_of(nv, kNone), full_of;
  std::vector<std::uint8_t> rim(nv, 0);
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
    const Tri& tr = mesh.triangles[t];
    const int n = inside[tr[0]] + inside[tr[1]] + inside[tr[2]];
    if (n == 3) {
      tris.push_back(t);
      continue;
    }
    // A vertex with a triangle outside is held: the springs may not pull the rest apart.
    for (std::uint32_t v : tr) rim[v] = 1;
  }
  if (tris.empty()) return out;
  Mesh sub;
  for (std::uint32_t t : tris) {
    Tri st{};
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[t][k];
      if (sub_of[v] == kNone) {
        sub_of[v] = static_cast<std::uint32_t>(full_of.size());
        full_of.push_back(v);
        sub.positions.push_back(mesh.positions[v]);
        sub.is_boundary.push_back(rim[v] || (!mesh.is_boundary.empty() && mesh.is_boundary[v]));
      }
      st[k] = sub_of[v];
    }
    sub.triangles.push_back(st);
  }
  // The singular curves' runs inside, so that the springs treat them as curves.
  for (const MeshCurve& c : mesh.curves) {
    MeshCurve run{.kind = c.kind, .vertices = {}, .closed = false};
    auto flush = [&] {
      if (run.vertices.size() >= 2) sub.curves.push_back(run);
      run.vertices.clear();
    };
    for (std::uint32_t v : c.vertices) {
      if (sub_of[v] == kNone) {
        flush();
        continue;
      }
      run.vertices.push_back(sub_of[v]);
    }
    flush();
  }

  ImproveOptions io;
  io.boundary = BoundaryMode::kFixed;
  io.threads = opt.threads;
  const ImproveStats st = improve_mesh(sub, surface, io, stop);
  out.converged = st.converged;
  out.steps = st.steps;
  // The improver moves vertices and flips edges; it neither adds nor removes any.
  if (sub.triangles.size() != tris.size() || sub.positions.size() != full_of.size())
    throw std::logic_error("improve_near_pinch_points: the improver changed the vertex count");
  // A flip between two held rim vertices could make an edge that a triangle outside has too:
  // then the mesh stays as it was (and the remesher relaxes it like the rest). Edges of three
  // or more triangles that were there before (a crossing the singular-set search missed) do
  // not count.
  auto edge_uses = [&] {
    std::unordered_map<std::uint64_t, int> uses;
    for (const Tri& tr : mesh.triangles)
      if (sub_of[tr[0]] != kNone || sub_of[tr[1]] != kNone || sub_of[tr[2]] != kNone)
        for (int k = 0; k < 3; ++k) ++uses[edge_key(tr[k], tr[(k + 1) % 3])];
    return uses;
  };
  const std::unordered_map<std::uint64_t, int> uses_before = edge_uses();
  std::vector<Tri> before(tris.size());
  for (size_t k = 0; k < tris.size(); ++k) {
    before[k] = mesh.triangles[tris[k]];
    for (int j = 0; j < 3; ++j) mesh.triangles[tris[k]][j] = full_of[sub.triangles[k][j]];
  }
  for (const auto& [e, n] : edge_uses()) {
    if (n <= 2) continue;
    const auto was = uses_before.find(e);
    if (was != uses_before.end() && was->second >= n) continue;
    for (size_t k = 0; k < tris.size(); ++k) mesh.triangles[tris[k]] = before[k];
    return out;
  }
  out.improved = true;
  for (size_t k = 0; k < full_of.size(); ++k) mesh.positions[full_of[k]] = sub.positions[k];
  for (size_t v = 0; v < nv; ++v)
    if (within(mesh.positions[v], pinches, kPinchHoldRadius * L))
      out.held.push_back(static_cast<std::uint32_t>(v));
  return out;
}

}  // namespace zeroset::detail
