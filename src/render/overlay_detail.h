#pragma once
// The singular-set overlay prepared for one picture: the curves' segments as capsules (a
// cylinder with a half-sphere at each end, so consecutive segments join smoothly) and the
// special points as spheres, binned into screen tiles by their projected boxes. Sample rays
// meet them exactly; a hit replaces the sample's surface hit when it is nearer. Private to
// the render module.
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "bins_detail.h"
#include "render_detail.h"
#include "zeroset/render/overlay.h"

namespace zeroset::detail {

/// A sample's nearest hit so far: ray parameter (in units of the sample ray's direction) and
/// the overlay primitive hit, -1 for none (t is then the surface's hit, or infinity).
struct OverlayHit {
  double t = std::numeric_limits<double>::infinity();
  std::int32_t primitive = -1;
};

class OverlayScene {
 public:
  /// The tubes and spheres of `overlay` (radii resolved against `scene_radius`) for `view`,
  /// shaded with `options`' lights. Throws InvalidArgument for a negative or non-finite radius.
  OverlayScene(const SingularOverlay& overlay, double scene_radius, const View& view,
               const RenderOptions& options);

  bool empty() const { return primitives_.empty(); }

  /// For the samples of the pixels [x0, x1) × [y0, y1) that the primitives' boxes cover: the
  /// nearest overlay hit along the ray eye + t·ray(x, y, s) nearer than depth(x, y, s) (the
  /// picture's own hit in units of that ray, infinity for none), where s < ns numbers the
  /// pixel's samples. Such a pixel is marked in touched[(y − y0)(x1 − x0) + x − x0], which
  /// the caller clears, and its samples' entries hits[k], k = ((y − y0)(x1 − x0) + x − x0)·ns
  /// + s, are set; the other entries are left alone. Only the pixels of the primitives' boxes
  /// are visited: the cost follows the overlay's screen area.
  template <class Ray, class Depth>
  void trace(int x0, int y0, int x1, int y1, int ns, const Ray& ray, const Depth& depth,
             std::uint8_t* touched, OverlayHit* hits) const;

  /// The colour of a hit found by trace along `ray` (any length).
  Color shade(const OverlayHit& hit, const Vec3& ray) const;

 private:
  struct Primitive {
    Vec3 a, b;  // a segment's ends; a sphere's centre twice
    double radius = 0;
    bool sphere = false;
    int shader = 0;
  };
  /// Nearest t in (0, t) where eye + t·dir meets primitive p; false when there is none.
  bool intersect(const Primitive& p, const Vec3& dir, double& t) const;

  Vec3 eye_;
  std::vector<Primitive> primitives_;
  Bins bins_;
  std::vector<Shader> shaders_;  // one per colour
};

/// The overlay `options` ask for (RenderOptions::singular_overlay), if any.
std::optional<OverlayScene> make_overlay(const RenderOptions& options, double scene_radius,
                                         const View& view);

template <class Ray, class Depth>
void OverlayScene::trace(int x0, int y0, int x1, int y1, int ns, const Ray& ray, const Depth& depth,
                         std::uint8_t* touched, OverlayHit* hits) const {
  if (primitives_.empty()) return;
  const int w = x1 - x0;
  for (int ty = y0 - y0 % kTile; ty < y1; ty += kTile)
    for (int tx = x0 - x0 % kTile; tx < x1; tx += kTile)
      for (std::uint32_t id : bins_.at(tx, ty)) {
        // The primitive's box within this tile and the region: each pixel once per primitive.
        const Bins::Rect& r = bins_.rects[id];
        const Primitive& p = primitives_[id];
        const int ya = std::max({r.y0, ty, y0}), yb = std::min({r.y1, ty + kTile - 1, y1 - 1});
        const int xa = std::max({r.x0, tx, x0}), xb = std::min({r.x1, tx + kTile - 1, x1 - 1});
        for (int y = ya; y <= yb; ++y)
          for (int x = xa; x <= xb; ++x) {
            const size_t pixel = static_cast<size_t>((y - y0) * w + (x - x0));
            OverlayHit* h = hits + pixel * static_cast<size_t>(ns);
            if (!touched[pixel]) {
              touched[pixel] = 1;
              for (int s = 0; s < ns; ++s) h[s] = {depth(x, y, s), -1};
            }
            for (int s = 0; s < ns; ++s)
              if (intersect(p, ray(x, y, s), h[s].t))
                h[s].primitive = static_cast<std::int32_t>(id);
          }
      }
}

inline bool OverlayScene::intersect(const Primitive& p, const Vec3& dir, double& t) const {
  const double dd = dir.squaredNorm();
  const double r2 = p.radius * p.radius;
  // The nearer root of |eye + t·dir − c|² = r² (a sphere at c), when it lies in (0, t).
  auto sphere = [&](const Vec3& oc, double& hit) {
    const double b = dir.dot(oc), c = oc.squaredNorm() - r2;
    const double h = b * b - dd * c;
    if (h < 0) return false;
    const double root = (-b - std::sqrt(h)) / dd;
    if (!(root > 0 && root < hit)) return false;
    hit = root;
    return true;
  };
  const Vec3 oa = eye_ - p.a;
  if (p.sphere) return sphere(oa, t);
  // The infinite cylinder around the axis a–b: |(o + t·d) × ba|² = r²·|ba|², in the form of
  // Quilez's ray–capsule test written for a direction of any length.
  const Vec3 ba = p.b - p.a;
  const double baba = ba.squaredNorm(), bard = ba.dot(dir), baoa = ba.dot(oa);
  const double a = baba * dd - bard * bard;
  if (a > 1e-14 * baba * dd) {
    const double b = baba * dir.dot(oa) - baoa * bard;
    const double c = baba * oa.squaredNorm() - baoa * baoa - r2 * baba;
    const double h = b * b - a * c;
    if (h < 0) return false;  // the ray passes farther than r from the axis: no cap either
    const double root = (-b - std::sqrt(h)) / a;
    const double y = baoa + root * bard;  // where along the axis, times |ba|
    if (y > 0 && y < baba) {
      if (!(root > 0 && root < t)) return false;
      t = root;
      return true;
    }
    // Beyond an end the ray enters through that end's half-sphere, if at all.
    return sphere(y <= 0 ? oa : Vec3(eye_ - p.b), t);
  }
  // Along the axis: it meets the nearer cap first.
  bool any = sphere(oa, t);
  any |= sphere(eye_ - p.b, t);
  return any;
}

}  // namespace zeroset::detail
