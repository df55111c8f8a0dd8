// Rays through fields that are not polynomials (or with RaycastOptions::force_interval):
// interval subdivision of the ray, then a bracketed refinement of the first sign change.
#include <algorithm>
#include <cmath>
#include <optional>

#include "raycast_detail.h"
#include "zeroset/detail/bracket.h"

namespace zeroset::detail {

std::optional<double> interval_hit(RayCaster& rc, const Vec3& origin, const Vec3& dir, double t0,
                                   double t1) {
  const double leaf = std::max(rc.options.interval_tolerance, 1e-15) * (t1 - t0);
  const double tol = 1e-13 * (t1 - t0);
  auto f = [&](double t) { return value_on_ray(rc, origin, dir, t); };
  rc.segments.clear();
  rc.segments.push_back({t0, t1});
  int budget = rc.options.interval_budget;
  while (!rc.segments.empty()) {
    if (--budget < 0) {  // F undefined or unbounded along the ray: give it up as a miss
      ++rc.abandoned_rays;
      return std::nullopt;
    }
    const Segment s = rc.segments.back();
    rc.segments.pop_back();
    Interval box[3];
    for (int k = 0; k < 3; ++k) {
      const double u = origin[k] + s.a * dir[k], v = origin[k] + s.b * dir[k];
      box[k] = {std::min(u, v), std::max(u, v)};
    }
    Interval e[4];  // F, Fx, Fy, Fz over the segment's box
    rc.intervals->eval_gradient(box[0], box[1], box[2], e);
    if (e[0].is_empty() || !e[0].contains_zero()) continue;
    // F along the ray has derivative ∇F·dir: when its enclosure excludes 0, F is monotone on
    // the segment, so the end values decide (one root or none) without subdividing.
    Interval slope{0, 0};
    for (int k = 0; k < 3; ++k) {
      const double lo = e[k + 1].lo * dir[k], hi = e[k + 1].hi * dir[k];
      slope.lo += std::min(lo, hi);
      slope.hi += std::max(lo, hi);
    }
    const bool finite_slope = std::isfinite(slope.lo) && std::isfinite(slope.hi);
    const bool monotone = finite_slope && !slope.contains_zero();
    if (finite_slope && !monotone) {
      // Mean value form, tighter than the direct enclosure on short segments:
      // F(t) ∈ F(m) + slope · [a − m, b − m].
      const double m = 0.5 * (s.a + s.b), fm = f(m), h = 0.5 * (s.b - s.a);
      const double reach = std::max(std::abs(slope.lo), std::abs(slope.hi)) * h;
      if (std::isfinite(fm) && std::abs(fm) > reach * (1 + 1e-12)) continue;
    }
    if (monotone || s.b - s.a <= leaf) {
      const double fa = f(s.a), fb = f(s.b);
      if (fa == 0) return s.a;
      if (std::isfinite(fa) && std::isfinite(fb) && (fa > 0) != (fb > 0))
        return refine_sign_change(f, s.a, s.b, fa, fb, tol);
      continue;
    }
    const double m = 0.5 * (s.a + s.b);
    rc.segments.push_back({m, s.b});
    rc.segments.push_back({s.a, m});
  }
  return std::nullopt;
}

}  // namespace zeroset::detail
