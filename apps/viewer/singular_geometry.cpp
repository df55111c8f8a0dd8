#include "singular_geometry.h"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace zeroset::viewer {
namespace {

// Tubes are a few pixels wide on screen: eight sides look round there.
constexpr int kTubeSides = 8;
constexpr int kSphereStacks = 8;
constexpr int kSphereSlices = 12;
// Consecutive curve vertices whose direction turns by less than 2° share a tube segment.
const double kMergeCos = std::cos(2 * std::numbers::pi / 180);

class Builder {
 public:
  explicit Builder(OverlayGeometry& g) : g_(g) {}

  void begin(const Color& color) {
    g_.batches.push_back({color, static_cast<std::uint32_t>(g_.indices.size()), 0});
  }
  void end() {
    OverlayGeometry::Batch& b = g_.batches.back();
    b.count = static_cast<std::uint32_t>(g_.indices.size()) - b.first;
    if (b.count == 0) g_.batches.pop_back();
  }

  void sphere(const Vec3& c, double r) {
    const std::uint32_t base = next();
    for (int i = 0; i <= kSphereStacks; ++i) {
      const double theta = std::numbers::pi * i / kSphereStacks;
      for (int j = 0; j <= kSphereSlices; ++j) {
        const double phi = 2 * std::numbers::pi * j / kSphereSlices;
        const Vec3 n(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                     std::cos(theta));
        vertex(c + r * n, n);
      }
    }
    const std::uint32_t row = kSphereSlices + 1;
    for (std::uint32_t i = 0; i < kSphereStacks; ++i)
      for (std::uint32_t j = 0; j < kSphereSlices; ++j)
        quad(base + i * row + j, base + i * row + j + 1, base + (i + 1) * row + j + 1,
             base + (i + 1) * row + j);
  }

  /// A tube of radius r along the polyline p (at least two distinct points), with a sphere on
  /// each end unless it is closed.
  void tube(const std::vector<Vec3>& p, double r, bool closed) {
    const size_t n = p.size();
    Vec3 u = Vec3::Zero();
    const std::uint32_t base = next();
    for (size_t i = 0; i < n; ++i) {
      // A closed curve's ends are one vertex: its rings there take both neighbours too.
      const size_t before = i > 0 ? i - 1 : closed ? n - 2 : n;
      const size_t after = i + 1 < n ? i + 1 : closed ? 1 : n;
      const Vec3 in = before < n ? Vec3((p[i] - p[before]).normalized()) : Vec3::Zero();
      const Vec3 out = after < n ? Vec3((p[after] - p[i]).normalized()) : Vec3::Zero();
      Vec3 t = in + out;
      if (t.norm() < 1e-9) t = out.norm() > 0 ? out : in;  // an end, or a reversal
      t.normalize();
      // Parallel transport of the ring's frame, so the tube does not twist.
      u -= u.dot(t) * t;
      if (u.norm() < 1e-6) {
        const int k = std::abs(t.x()) < 0.6 ? 0 : std::abs(t.y()) < 0.6 ? 1 : 2;
        u = Vec3::Unit(k) - t[k] * t;
      }
      u.normalize();
      const Vec3 v = t.cross(u);
      for (int s = 0; s < kTubeSides; ++s) {
        const double a = 2 * std::numbers::pi * s / kTubeSides;
        const Vec3 normal = std::cos(a) * u + std::sin(a) * v;
        vertex(p[i] + r * normal, normal);
      }
    }
    for (std::uint32_t i = 0; i + 1 < n; ++i)
      for (std::uint32_t s = 0; s < kTubeSides; ++s) {
        const std::uint32_t s1 = (s + 1) % kTubeSides;
        quad(base + i * kTubeSides + s, base + i * kTubeSides + s1,
             base + (i + 1) * kTubeSides + s1, base + (i + 1) * kTubeSides + s);
      }
    if (!closed) {
      sphere(p.front(), r);
      sphere(p.back(), r);
    }
  }

 private:
  std::uint32_t next() const { return static_cast<std::uint32_t>(g_.vertex_count()); }
  void vertex(const Vec3& p, const Vec3& n) {
    for (int k = 0; k < 3; ++k) g_.vertices.push_back(static_cast<float>(p[k]));
    for (int k = 0; k < 3; ++k) g_.vertices.push_back(static_cast<float>(n[k]));
  }
  void quad(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
    g_.indices.insert(g_.indices.end(), {a, b, c, a, c, d});
  }

  OverlayGeometry& g_;
};

// The finite vertices of a curve, without repeats and with nearly collinear runs merged.
std::vector<Vec3> tube_path(const std::vector<Vec3>& points) {
  std::vector<Vec3> path;
  for (size_t i = 0; i < points.size(); ++i) {
    const Vec3& q = points[i];
    if (!q.allFinite() || (!path.empty() && q == path.back())) continue;
    if (path.size() >= 2) {
      // Drop the last kept vertex when the path goes on straight through it.
      const Vec3 before = (path.back() - path[path.size() - 2]).normalized();
      const Vec3 after = (q - path.back()).normalized();
      if (before.dot(after) > kMergeCos) path.pop_back();
    }
    path.push_back(q);
  }
  return path;
}

}  // namespace

OverlayGeometry singular_overlay_geometry(const SingularSet& set, const SingularOverlay& style,
                                          double scene_radius) {
  const double tube = style.tube_radius_for(scene_radius);
  const double point = style.point_radius_for(scene_radius);
  OverlayGeometry g;
  Builder b(g);
  if (tube > 0)
    for (const CurveKind kind :
         {CurveKind::kCrossing, CurveKind::kIsolated, CurveKind::kDegenerate}) {
      b.begin(style.color(kind));
      for (const SingularCurve& curve : set.curves) {
        if (curve.kind != kind) continue;
        std::vector<Vec3> path = tube_path(curve.points);
        if (curve.closed && path.size() >= 3 && path.front() != path.back())
          path.push_back(path.front());
        if (path.size() >= 2) b.tube(path, tube, curve.closed && path.size() >= 4);
      }
      b.end();
    }
  if (point > 0)
    for (const SingularPointKind kind :
         {SingularPointKind::kNode, SingularPointKind::kPinch, SingularPointKind::kTriple,
          SingularPointKind::kClipEnd, SingularPointKind::kDegenerate}) {
      b.begin(style.color(kind));
      for (const SingularPoint& p : set.points)
        if (p.kind == kind && p.position.allFinite()) b.sphere(p.position, point);
      b.end();
    }
  return g;
}

}  // namespace zeroset::viewer
