#include "zeroset/render/overlay.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "overlay_detail.h"
#include "zeroset/error.h"

namespace zeroset {

const Color& SingularOverlay::color(CurveKind kind) const {
  switch (kind) {
    case CurveKind::kCrossing:
      return crossing;
    case CurveKind::kIsolated:
      return isolated;
    case CurveKind::kDegenerate:
      return degenerate;
  }
  return crossing;
}

const Color& SingularOverlay::color(SingularPointKind kind) const {
  switch (kind) {
    case SingularPointKind::kNode:
      return node;
    case SingularPointKind::kPinch:
      return pinch;
    case SingularPointKind::kTriple:
      return triple;
    case SingularPointKind::kClipEnd:
      return clip_end;
    case SingularPointKind::kDegenerate:
      return degenerate_point;
  }
  return node;
}

namespace {

/// A radius as given, or `fraction` of the scene radius for 0.
double resolve_radius(double given, double fraction, double scene_radius, const char* what) {
  if (!(given >= 0) || !std::isfinite(given))
    throw InvalidArgument(what, std::to_string(given), "must be finite and not negative");
  return given > 0 ? given : fraction * scene_radius;
}

}  // namespace

double SingularOverlay::tube_radius_for(double scene_radius) const {
  return resolve_radius(tube_radius, 0.006, scene_radius, "singular overlay tube radius");
}

double SingularOverlay::point_radius_for(double scene_radius) const {
  return resolve_radius(point_radius, 0.015, scene_radius, "singular overlay point radius");
}

namespace detail {

OverlayScene::OverlayScene(const SingularOverlay& overlay, double scene_radius, const View& view,
                           const RenderOptions& options)
    : eye_(view.eye), bins_(view.width, view.height, 0) {
  const double tube = overlay.tube_radius_for(scene_radius);
  const double point = overlay.point_radius_for(scene_radius);

  // One shader per colour, lit like the surface with the overlay's Phong terms.
  std::vector<Color> colors;
  auto shader_of = [&](const Color& c) {
    for (size_t i = 0; i < colors.size(); ++i)
      if (colors[i] == c) return static_cast<int>(i);
    RenderOptions lit = options;
    lit.front = lit.back = Material{.diffuse = c,
                                    .ambient = overlay.ambient,
                                    .specular = overlay.specular,
                                    .shininess = overlay.shininess};
    colors.push_back(c);
    shaders_.emplace_back(lit, view);
    return static_cast<int>(colors.size() - 1);
  };

  if (tube > 0)
    for (const SingularCurve& curve : overlay.set.curves) {
      const int shader = shader_of(overlay.color(curve.kind));
      for (size_t i = 0; i + 1 < curve.points.size(); ++i) {
        const Vec3 &a = curve.points[i], &b = curve.points[i + 1];
        if (!a.allFinite() || !b.allFinite()) continue;
        primitives_.push_back({a, b, tube, a == b, shader});
      }
    }
  if (point > 0)
    for (const SingularPoint& p : overlay.set.points) {
      if (!p.position.allFinite()) continue;
      primitives_.push_back(
          {p.position, p.position, point, true, shader_of(overlay.color(p.kind))});
    }

  bins_.rects.resize(primitives_.size());
  for (size_t i = 0; i < primitives_.size(); ++i) {
    const Primitive& p = primitives_[i];
    const Vec3 lo = p.a.cwiseMin(p.b).array() - p.radius, hi = p.a.cwiseMax(p.b).array() + p.radius;
    Vec3 corners[8];
    for (int k = 0; k < 8; ++k)
      corners[k] = Vec3(k & 1 ? hi.x() : lo.x(), k & 2 ? hi.y() : lo.y(), k & 4 ? hi.z() : lo.z());
    bins_.add(static_cast<std::uint32_t>(i), corners, 8, view);
  }
}

Color OverlayScene::shade(const OverlayHit& hit, const Vec3& ray) const {
  const Primitive& p = primitives_[static_cast<size_t>(hit.primitive)];
  const Vec3 at = eye_ + hit.t * ray;
  Vec3 centre = p.a;  // the nearest point of the primitive's axis
  if (!p.sphere) {
    const Vec3 ba = p.b - p.a;
    centre += std::clamp((at - p.a).dot(ba) / ba.squaredNorm(), 0.0, 1.0) * ba;
  }
  Vec3 n = at - centre;
  const double length = n.norm();
  const Vec3 dir = ray.normalized();
  n = length > 0 ? Vec3(n / length) : Vec3(-dir);
  return shaders_[static_cast<size_t>(p.shader)].shade(n, dir, true);
}

std::optional<OverlayScene> make_overlay(const RenderOptions& options, double scene_radius,
                                         const View& view) {
  if (!options.singular_overlay) return std::nullopt;
  if (view.orthographic)
    throw InvalidArgument("singular overlay", "orthographic camera",
                          "the overlay is drawn with a perspective camera only");
  return std::optional<OverlayScene>(std::in_place, *options.singular_overlay, scene_radius, view,
                                     options);
}

}  // namespace detail
}  // namespace zeroset
