#include "zeroset/surface/clip.h"

#include <fmt/core.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <limits>

#include "zeroset/error.h"

namespace zeroset {
namespace {

std::vector<double> parse_numbers(std::string_view text, std::string_view spec) {
  std::vector<double> out;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t comma = text.find(',', pos);
    if (comma == std::string_view::npos) comma = text.size();
    std::string item(text.substr(pos, comma - pos));
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || end != item.c_str() + item.size() || !std::isfinite(v))
      throw InvalidArgument("--clip", std::string(spec),
                            fmt::format("'{}' is not a finite number", item));
    out.push_back(v);
    pos = comma + 1;
  }
  return out;
}

// Bounding box from the spheres and the axis-aligned planes (infinite where they leave it
// open). Oblique planes only ever shrink the volume, so the box stays a valid bound.
Box3 raw_bounds(const Clip& clip) {
  Box3 b{Vec3::Constant(-std::numeric_limits<double>::infinity()),
         Vec3::Constant(std::numeric_limits<double>::infinity())};
  for (const auto& s : clip.spheres) {
    b.lo = b.lo.cwiseMax(s.center - Vec3::Constant(s.radius));
    b.hi = b.hi.cwiseMin(s.center + Vec3::Constant(s.radius));
  }
  for (const auto& h : clip.planes) {
    for (int k = 0; k < 3; ++k) {
      Vec3 e = Vec3::Zero();
      e[k] = 1;
      if (h.normal.isApprox(e, 1e-12)) b.hi[k] = std::min(b.hi[k], h.offset);
      if (h.normal.isApprox(-e, 1e-12)) b.lo[k] = std::max(b.lo[k], -h.offset);
    }
  }
  return b;
}

// The smallest size allowed for a part whose coordinates reach `magnitude`.
double min_size(double magnitude) { return kMinClipRelativeSize * std::max(1.0, magnitude); }

void check_coordinates(std::initializer_list<double> values, const std::string& spec) {
  for (double v : values)
    if (!(std::abs(v) <= kMaxClipCoordinate))
      throw InvalidArgument("--clip", spec,
                            fmt::format("{:g} is beyond the clip coordinates' range [-{:g}, {:g}]",
                                        v, kMaxClipCoordinate, kMaxClipCoordinate));
}

// A box's sides (also the bounding box of a whole clip): at least min_size of its corners.
void check_box(const Box3& b, const std::string& spec, const char* what) {
  const double magnitude = std::max(b.lo.cwiseAbs().maxCoeff(), b.hi.cwiseAbs().maxCoeff());
  const double side = (b.hi - b.lo).minCoeff();
  if (!(side >= min_size(magnitude)))
    throw InvalidArgument(
        "--clip", spec,
        side < 0 ? fmt::format("{} is empty", what)
                 : fmt::format("{}'s sides must be at least {:g} times max(1, its largest "
                               "coordinate), here {:g}; the side {:g} is too small to hold "
                               "distinct points",
                               what, kMinClipRelativeSize, min_size(magnitude), side));
}

constexpr const char* kClipHelp =
    "expected sphere:R, sphere:R@cx,cy,cz, box:H, box:x0,y0,z0,x1,y1,z1 or plane:nx,ny,nz,d";

}  // namespace

Clip Clip::sphere(double radius, const Vec3& center) {
  Clip c;
  c.spheres.push_back({center, radius});
  return c;
}

Clip Clip::box(const Box3& b) {
  Clip c;
  for (int k = 0; k < 3; ++k) {
    Vec3 n = Vec3::Zero();
    n[k] = 1;
    c.planes.push_back({n, b.hi[k]});
    c.planes.push_back({-n, -b.lo[k]});
  }
  return c;
}

void Clip::add(std::string_view spec) {
  const std::string s(spec);
  const size_t colon = spec.find(':');
  if (colon == std::string_view::npos) throw InvalidArgument("--clip", s, kClipHelp);
  const std::string_view kind = spec.substr(0, colon);
  std::string_view rest = spec.substr(colon + 1);
  const std::size_t adds = kind == "box" ? 6 : 1;
  if (spheres.size() + planes.size() + adds > kMaxClipParts)
    throw InvalidArgument("--clip", s,
                          fmt::format("a clip has at most {} parts (a sphere or plane is one, a "
                                      "box six)",
                                      kMaxClipParts));
  if (kind == "sphere") {
    Vec3 center = Vec3::Zero();
    const size_t at = rest.find('@');
    if (at != std::string_view::npos) {
      auto c = parse_numbers(rest.substr(at + 1), spec);
      if (c.size() != 3) throw InvalidArgument("--clip", s, "the centre needs three numbers");
      center = Vec3(c[0], c[1], c[2]);
      rest = rest.substr(0, at);
    }
    auto r = parse_numbers(rest, spec);
    if (r.size() != 1 || r[0] <= 0)
      throw InvalidArgument("--clip", s, "a sphere needs one positive radius");
    // Refused, not rescaled: see kMinClipRelativeSize and kMaxClipCoordinate.
    check_coordinates({r[0], center.x(), center.y(), center.z()}, s);
    const double smallest = min_size(center.cwiseAbs().maxCoeff());
    if (r[0] < smallest)
      throw InvalidArgument("--clip", s,
                            fmt::format("the radius must be at least {:g} times max(1, the "
                                        "centre's largest coordinate), here {:g}",
                                        kMinClipRelativeSize, smallest));
    spheres.push_back({center, r[0]});
  } else if (kind == "box") {
    auto v = parse_numbers(rest, spec);
    Box3 b;
    if (v.size() == 1 && v[0] > 0) {
      b = Box3::cube(v[0]);
    } else if (v.size() == 6) {
      b = {Vec3(v[0], v[1], v[2]), Vec3(v[3], v[4], v[5])};
      if ((b.lo.array() >= b.hi.array()).any())
        throw InvalidArgument("--clip", s, "a box needs x0 < x1, y0 < y1, z0 < z1");
    } else {
      throw InvalidArgument("--clip", s, "a box needs one positive half size or six numbers");
    }
    check_coordinates({b.lo.x(), b.lo.y(), b.lo.z(), b.hi.x(), b.hi.y(), b.hi.z()}, s);
    check_box(b, s, "the box");
    Clip c = Clip::box(b);
    planes.insert(planes.end(), c.planes.begin(), c.planes.end());
  } else if (kind == "plane") {
    auto v = parse_numbers(rest, spec);
    if (v.size() != 4) throw InvalidArgument("--clip", s, "a plane needs nx,ny,nz,d");
    Vec3 n(v[0], v[1], v[2]);
    // Scaled to its largest component first, so that neither 1e-300 nor 1e300 components
    // under- or overflow the length.
    const double largest = n.cwiseAbs().maxCoeff();
    if (!(largest > 0)) throw InvalidArgument("--clip", s, "the plane normal must not be zero");
    n /= largest;
    const double len = n.norm();
    const double offset = v[3] / largest / len;
    check_coordinates({offset}, s);
    planes.push_back({n / len, offset});
  } else {
    throw InvalidArgument("--clip", s, kClipHelp);
  }
}

void Clip::check_extent() const {
  Box3 b = raw_bounds(*this);
  // Only the bounded directions: an axis left open by oblique planes has no side to check.
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(b.lo[k]) || !std::isfinite(b.hi[k])) b.lo[k] = 0, b.hi[k] = 1;
  try {
    check_box(b, "", "the clip volume");
  } catch (const InvalidArgument&) {
    std::string all;  // the specs, shortened: a scene may hold very many
    for (const auto& spec : to_specs()) {
      if (all.size() > 200) {
        all += " ...";
        break;
      }
      all += (all.empty() ? "" : " ") + spec;
    }
    check_box(b, all, "the clip volume");
  }
}

bool Clip::is_bounded() const {
  const Box3 b = raw_bounds(*this);
  return b.lo.allFinite() && b.hi.allFinite();
}

bool Clip::contains(const Vec3& p, double tolerance) const { return value(p) <= tolerance; }

double Clip::value(const Vec3& p) const {
  Vec3 g;
  return value_gradient(p, g);
}

double Clip::value_gradient(const Vec3& p, Vec3& gradient) const {
  double best = -std::numeric_limits<double>::infinity();
  gradient = Vec3::Zero();
  for (const auto& s : spheres) {
    const Vec3 d = p - s.center;
    const double len = d.norm();
    const double g = len - s.radius;
    if (g > best) {
      best = g;
      gradient = len > 0 ? Vec3(d / len) : Vec3(Vec3::UnitZ());
    }
  }
  for (const auto& h : planes) {
    const double g = h.normal.dot(p) - h.offset;
    if (g > best) {
      best = g;
      gradient = h.normal;
    }
  }
  return best;
}

Vec3 Clip::project(const Vec3& p) const {
  // Projecting onto one violated part can violate another (a box corner); a few rounds settle
  // it for convex intersections of these simple parts.
  Vec3 q = p;
  for (int round = 0; round < 8; ++round) {
    bool moved = false;
    for (const auto& h : planes) {
      const double g = h.normal.dot(q) - h.offset;
      if (g > 0) {
        q -= g * h.normal;
        moved = true;
      }
    }
    for (const auto& s : spheres) {
      const Vec3 d = q - s.center;
      // Well inside (by far more than rounding): no square root needed.
      if (d.squaredNorm() < s.radius * s.radius * (1 - 1e-12)) continue;
      const double len = d.norm();
      if (len > s.radius) {
        q = s.center + d * (s.radius / len);
        moved = true;
      }
    }
    if (!moved) break;
  }
  return q;
}

Box3 Clip::bounds() const {
  const Box3 b = raw_bounds(*this);
  if (!b.lo.allFinite() || !b.hi.allFinite())
    throw BadInput(
        "the clip volume is unbounded; give a bounded clip such as --clip sphere:2 or --clip "
        "box:2");
  return b;
}

bool Clip::ray_interval(const Vec3& o, const Vec3& d, double t_min, double& t0,
                        double& t1) const {
  t0 = t_min;
  t1 = std::numeric_limits<double>::infinity();
  for (const auto& s : spheres) {
    const Vec3 oc = o - s.center;
    const double a = d.squaredNorm();
    const double b = oc.dot(d);
    const double c = oc.squaredNorm() - s.radius * s.radius;
    const double disc = b * b - a * c;
    if (disc < 0) return false;
    const double sq = std::sqrt(disc);
    // Numerically stable roots.
    const double qv = -(b + std::copysign(sq, b));
    double r0 = qv / a, r1 = qv != 0 ? c / qv : -b / a;
    if (r0 > r1) std::swap(r0, r1);
    t0 = std::max(t0, r0);
    t1 = std::min(t1, r1);
  }
  for (const auto& h : planes) {
    const double nd = h.normal.dot(d);
    const double g = h.normal.dot(o) - h.offset;
    if (nd == 0) {
      if (g > 0) return false;
      continue;
    }
    const double t = -g / nd;
    if (nd > 0)
      t1 = std::min(t1, t);
    else
      t0 = std::max(t0, t);
  }
  return t0 < t1;
}

std::vector<std::string> Clip::to_specs() const {
  std::vector<std::string> out;
  for (const auto& s : spheres) {
    if (s.center.isZero())
      out.push_back(fmt::format("sphere:{}", s.radius));
    else
      out.push_back(
          fmt::format("sphere:{}@{},{},{}", s.radius, s.center.x(), s.center.y(), s.center.z()));
  }
  for (const auto& h : planes)
    out.push_back(
        fmt::format("plane:{},{},{},{}", h.normal.x(), h.normal.y(), h.normal.z(), h.offset));
  return out;
}

}  // namespace zeroset
