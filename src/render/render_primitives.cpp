// Point sets as shaded disks and triangle meshes: primitives are binned into screen tiles by
// their projected bounding boxes; each tile then intersects the rays of its samples with the
// primitives in its bin (exact ray–disk and ray–triangle tests, nearest hit wins), so the
// picture has the same camera, samples and shading as the ray-cast surface.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "bins_detail.h"
#include "overlay_detail.h"
#include "render_detail.h"
#include "zeroset/error.h"
#include "zeroset/render/render.h"

namespace zeroset {
namespace {

using detail::Bins;
using detail::kTile;

/// The nearest hit of one sample ray.
struct SampleHit {
  double t = std::numeric_limits<double>::infinity();
  Vec3 normal = Vec3::UnitZ();
  bool front = true;
  bool edge = false;
};

/// Renders binned primitives: `intersect(id, origin, dir, hit)` returns true and fills `hit`
/// when the ray from `origin` (the eye, or a point of its plane when orthographic) along `dir`
/// meets primitive `id` nearer than hit.t. Each tile keeps the
/// nearest hit of every sample (a z-buffer) and visits, per primitive of its bin, only the
/// pixels of that primitive's bounding box, so the cost follows the primitives' screen area.
/// The singular overlay, when given, then replaces the samples it is nearer on.
template <class Intersect>
Image render_binned(const RenderOptions& options, const View& view, const Bins& bins,
                    const Intersect& intersect, const detail::OverlayScene* overlay) {
  const detail::Shader shader(options, view);
  const std::vector<Vec2> offsets = detail::sample_offsets(options.samples);
  const int ns = static_cast<int>(offsets.size());
  const double weight = 1.0 / ns;
  const Color edge_color(0.05, 0.05, 0.05);
  Image image(options.width, options.height);
  detail::for_each_tile(
      options.width, options.height, kTile, kTile, detail::thread_count(options.threads), {},
      options.progress, [&](int x0, int y0, int x1, int y1, int) {
        const int w = x1 - x0;
        std::vector<SampleHit> hits(static_cast<size_t>(w) * (y1 - y0) * ns);
        std::vector<std::uint8_t> any(hits.size(), 0);
        auto sample = [&](int x, int y, int s) {
          return static_cast<size_t>(((y - y0) * w + (x - x0)) * ns + s);
        };
        std::vector<Vec3> dirs(hits.size());  // each sample's ray, shared by the primitives
        std::vector<Vec3> origins(view.orthographic ? hits.size() : 0);
        for (int y = y0; y < y1; ++y)
          for (int x = x0; x < x1; ++x)
            for (int s = 0; s < ns; ++s) {
              const double sx = x + offsets[static_cast<size_t>(s)].x(),
                           sy = y + offsets[static_cast<size_t>(s)].y();
              dirs[sample(x, y, s)] = view.direction(sx, sy);
              if (view.orthographic) origins[sample(x, y, s)] = view.origin(sx, sy);
            }
        for (std::uint32_t id : bins.at(x0, y0)) {
          const Bins::Rect& r = bins.rects[id];
          for (int y = std::max(r.y0, y0); y <= std::min(r.y1, y1 - 1); ++y)
            for (int x = std::max(r.x0, x0); x <= std::min(r.x1, x1 - 1); ++x)
              for (int s = 0; s < ns; ++s) {
                const size_t k = sample(x, y, s);
                if (intersect(id, view.orthographic ? origins[k] : view.eye, dirs[k], hits[k]))
                  any[k] = 1;
              }
        }
        // The overlay's hits where they are nearer than hits[k] (entries of touched pixels).
        std::vector<detail::OverlayHit> on_top;
        std::vector<std::uint8_t> touched;
        if (overlay) {
          on_top.resize(hits.size());
          touched.assign(static_cast<size_t>(w * (y1 - y0)), 0);
          overlay->trace(
              x0, y0, x1, y1, ns,
              [&](int x, int y, int s) -> const Vec3& { return dirs[sample(x, y, s)]; },
              [&](int x, int y, int s) { return hits[sample(x, y, s)].t; }, touched.data(),
              on_top.data());
        }
        for (int y = y0; y < y1; ++y)
          for (int x = x0; x < x1; ++x) {
            Color sum = Color::Zero();
            for (int s = 0; s < ns; ++s) {
              const size_t k = sample(x, y, s);
              const SampleHit& hit = hits[k];
              if (!touched.empty() && touched[k / static_cast<size_t>(ns)] &&
                  on_top[k].primitive >= 0) {
                sum += overlay->shade(on_top[k], dirs[k]);
              } else if (!any[k]) {
                sum += options.background;
              } else if (hit.edge) {
                sum += edge_color;
              } else {
                sum += shader.shade(hit.normal, dirs[k], hit.front);
              }
            }
            detail::store_linear(image, x, y, sum * weight);
          }
      });
  return image;
}

}  // namespace

Image render_points(const Surface& surface, std::span<const Vec3> positions,
                    std::span<const Vec3> normals, std::span<const double> radii,
                    const RenderOptions& options) {
  detail::validate(options);
  if (!normals.empty() && normals.size() != positions.size())
    throw InvalidArgument("normals", std::to_string(normals.size()),
                          "need one per point (" + std::to_string(positions.size()) + ")");
  if (!radii.empty() && radii.size() != positions.size())
    throw InvalidArgument("radii", std::to_string(radii.size()),
                          "need one per point (" + std::to_string(positions.size()) + ")");
  const double scene = surface.scene_radius();
  const View view =
      View::from_camera(detail::camera_of(surface, options), scene, options.width, options.height);
  // Without radii: disks that roughly cover a surface of the scene's size.
  const double default_radius =
      2.0 * scene / std::sqrt(static_cast<double>(std::max<size_t>(positions.size(), 1)));
  auto radius = [&](size_t i) { return radii.empty() ? default_radius : radii[i]; };
  auto normal = [&](size_t i) -> Vec3 {
    if (!normals.empty() && normals[i].allFinite() && normals[i].norm() > 0)
      return normals[i].normalized();
    return -view.forward;  // no normal: a disk facing the camera
  };

  Bins bins(options.width, options.height, positions.size());
  for (size_t i = 0; i < positions.size(); ++i) {
    const double r = radius(i);
    if (!(r > 0) || !positions[i].allFinite()) continue;
    Vec3 corners[8];
    for (int k = 0; k < 8; ++k)
      corners[k] = positions[i] + r * Vec3(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1);
    bins.add(static_cast<std::uint32_t>(i), corners, 8, view);
  }
  const std::optional<detail::OverlayScene> overlay = detail::make_overlay(options, scene, view);
  return render_binned(
      options, view, bins,
      [&](std::uint32_t id, const Vec3& eye, const Vec3& dir, SampleHit& hit) {
        const Vec3 n = normal(id);
        const double nd = n.dot(dir);
        if (std::abs(nd) < 1e-12) return false;
        const double t = n.dot(positions[id] - eye) / nd;
        if (!(t > 0 && t < hit.t)) return false;
        const double r = radius(id);
        if ((eye + t * dir - positions[id]).squaredNorm() > r * r) return false;
        hit.t = t;
        hit.front = nd < 0;
        hit.normal = hit.front ? n : Vec3(-n);
        hit.edge = false;
        return true;
      },
      overlay ? &*overlay : nullptr);
}

Image render_mesh(const Surface& surface, const Mesh& mesh, const RenderOptions& options,
                  bool wireframe) {
  detail::validate(options);
  const View view = View::from_camera(detail::camera_of(surface, options), surface.scene_radius(),
                                      options.width, options.height);
  const size_t nv = mesh.positions.size();
  for (const auto& tri : mesh.triangles)
    for (std::uint32_t v : tri)
      if (v >= nv)
        throw InvalidArgument("mesh", "vertex index " + std::to_string(v),
                              "out of range (" + std::to_string(nv) + " vertices)");

  // Vertex normals: the mesh's own, else ∇F at the vertex; where ∇F vanishes (a node) the
  // area-weighted average of the adjacent faces, which follows the triangles' orientation.
  std::vector<Vec3> face_sum(nv, Vec3::Zero());
  for (const auto& tri : mesh.triangles) {
    const Vec3& a = mesh.positions[tri[0]];
    const Vec3 n = (mesh.positions[tri[1]] - a).cross(mesh.positions[tri[2]] - a);
    for (std::uint32_t v : tri) face_sum[v] += n;
  }
  std::vector<Vec3> normals(nv, Vec3::Zero());
  const bool has_normals = mesh.normals.size() == nv;
  Evaluator evaluator(surface.field);
  for (size_t i = 0; i < nv; ++i) {
    Vec3 n = has_normals ? mesh.normals[i] : Vec3::Zero();
    if (!has_normals) evaluator.value_gradient(mesh.positions[i], n);
    if (!(n.allFinite() && n.norm() > 1e-12 * (1 + face_sum[i].norm()))) n = face_sum[i];
    normals[i] = n.norm() > 0 ? n.normalized() : Vec3::Zero();
  }

  Bins bins(options.width, options.height, mesh.triangles.size());
  for (size_t f = 0; f < mesh.triangles.size(); ++f) {
    const auto& tri = mesh.triangles[f];
    const Vec3 p[3] = {mesh.positions[tri[0]], mesh.positions[tri[1]], mesh.positions[tri[2]]};
    bins.add(static_cast<std::uint32_t>(f), p, 3, view);
  }
  // The size of a pixel at depth 1 (perspective) or at every depth (orthographic).
  const double pixel = view.orthographic ? view.pixel_size(1) : view.pixel_angle();
  const std::optional<detail::OverlayScene> overlay =
      detail::make_overlay(options, surface.scene_radius(), view);
  return render_binned(
      options, view, bins,
      [&](std::uint32_t id, const Vec3& eye, const Vec3& dir, SampleHit& hit) {
        // Möller–Trumbore.
        const auto& tri = mesh.triangles[id];
        const Vec3& a = mesh.positions[tri[0]];
        const Vec3 e1 = mesh.positions[tri[1]] - a, e2 = mesh.positions[tri[2]] - a;
        const Vec3 pv = dir.cross(e2);
        const double det = e1.dot(pv);
        if (std::abs(det) < 1e-300) return false;
        const double inv = 1.0 / det;
        const Vec3 tv = eye - a;
        const double u = tv.dot(pv) * inv;
        if (u < 0 || u > 1) return false;
        const Vec3 qv = tv.cross(e1);
        const double v = dir.dot(qv) * inv;
        if (v < 0 || u + v > 1) return false;
        const double t = e2.dot(qv) * inv;
        if (!(t > 0 && t < hit.t)) return false;
        const double w = 1 - u - v;
        const Vec3 ng = e1.cross(e2);
        Vec3 n = w * normals[tri[0]] + u * normals[tri[1]] + v * normals[tri[2]];
        if (!(n.norm() > 1e-12)) n = ng;
        n.normalize();
        hit.t = t;
        hit.front = ng.dot(dir) < 0;
        hit.normal = n.dot(dir) > 0 ? Vec3(-n) : n;
        hit.edge = false;
        if (wireframe) {
          // Distance to the nearest edge (barycentric coordinate × height over that edge),
          // compared with the size of a pixel at this depth: lines about one pixel wide.
          const double area2 = ng.norm();
          const Vec3 e3 = mesh.positions[tri[2]] - mesh.positions[tri[1]];
          const double d =
              std::min({w * area2 / e3.norm(), u * area2 / e2.norm(), v * area2 / e1.norm()});
          hit.edge = d < 0.7 * pixel * (view.orthographic ? 1.0 : t);
        }
        return true;
      },
      overlay ? &*overlay : nullptr);
}

}  // namespace zeroset
