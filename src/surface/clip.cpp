#include "zeroset/surface/clip.h"

#include <fmt/core.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <optional>

#include "zeroset/error.h"
#include "zeroset/expr/parse.h"

namespace zeroset {
namespace {

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

namespace {

// The spec's text split at commas outside parentheses (an expression may hold a comma only
// inside a call, none of the language's functions takes two arguments, yet a stray one should
// be reported by the expression parser, not split here).
std::vector<std::string> split_items(std::string_view text) {
  std::vector<std::string> out;
  int depth = 0;
  std::string item;
  for (char ch : text) {
    if (ch == '(') ++depth;
    if (ch == ')') --depth;
    if (ch == ',' && depth <= 0) {
      out.push_back(item);
      item.clear();
    } else {
      item += ch;
    }
  }
  out.push_back(item);
  return out;
}

// A plain number, or nullopt when the item must be read as an expression.
std::optional<double> plain_number(const std::string& item, const std::string& spec) {
  char* end = nullptr;
  const double v = std::strtod(item.c_str(), &end);
  if (item.empty()) throw InvalidArgument("--clip", spec, "'' is not a finite number");
  if (end != item.c_str() + item.size()) return std::nullopt;
  if (!std::isfinite(v))
    throw InvalidArgument("--clip", spec, fmt::format("'{}' is not a finite number", item));
  return v;
}

Field formula(const std::string& item, const std::string& spec) {
  ParseResult r = parse_field(item);
  if (!r.ok())
    throw InvalidArgument(
        "--clip", spec,
        fmt::format(
            "'{}' is neither a number nor an expression of the parameters: {}", item,
            r.diagnostics.empty() ? std::string("no expression") : r.diagnostics.front().message));
  if (r.field->depends_on_position())
    throw InvalidArgument("--clip", spec,
                          fmt::format("'{}' depends on x, y or z; a clip's numbers may depend "
                                      "on the surface's parameters only",
                                      item));
  return *r.field;
}

// Checks one spec's numbers and appends its parts (sphere: radius; box: 1 or 6 numbers;
// plane: 4). `center` is a sphere's centre when given.
void add_numbers(Clip& clip, std::string_view kind, const std::string& s,
                 const std::vector<double>& v, const std::vector<double>* center) {
  if (kind == "sphere") {
    Vec3 c = Vec3::Zero();
    if (center) {
      if (center->size() != 3) throw InvalidArgument("--clip", s, "the centre needs three numbers");
      c = Vec3((*center)[0], (*center)[1], (*center)[2]);
    }
    if (v.size() != 1 || !(v[0] > 0))
      throw InvalidArgument("--clip", s, "a sphere needs one positive radius");
    // Refused, not rescaled: see kMinClipRelativeSize and kMaxClipCoordinate.
    check_coordinates({v[0], c.x(), c.y(), c.z()}, s);
    const double smallest = min_size(c.cwiseAbs().maxCoeff());
    if (v[0] < smallest)
      throw InvalidArgument("--clip", s,
                            fmt::format("the radius must be at least {:g} times max(1, the "
                                        "centre's largest coordinate), here {:g}",
                                        kMinClipRelativeSize, smallest));
    clip.spheres.push_back({c, v[0]});
  } else if (kind == "box") {
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
    const Clip c = Clip::box(b);
    clip.planes.insert(clip.planes.end(), c.planes.begin(), c.planes.end());
  } else {
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
    clip.planes.push_back({n / len, offset});
  }
}

}  // namespace

void Clip::add(std::string_view spec) {
  const std::string s(spec);
  const size_t colon = spec.find(':');
  if (colon == std::string_view::npos) throw InvalidArgument("--clip", s, kClipHelp);
  const std::string_view kind = spec.substr(0, colon);
  if (kind != "sphere" && kind != "box" && kind != "plane")
    throw InvalidArgument("--clip", s, kClipHelp);
  std::string_view rest = spec.substr(colon + 1);
  const std::size_t adds = kind == "box" ? 6 : 1;
  if (spheres.size() + planes.size() + adds > kMaxClipParts)
    throw InvalidArgument("--clip", s,
                          fmt::format("a clip has at most {} parts (a sphere or plane is one, a "
                                      "box six)",
                                      kMaxClipParts));
  std::vector<std::string> items, center_items;
  const size_t at = kind == "sphere" ? rest.find('@') : std::string_view::npos;
  if (at != std::string_view::npos) {
    center_items = split_items(rest.substr(at + 1));
    rest = rest.substr(0, at);
  }
  items = split_items(rest);
  std::vector<double> v, center;
  std::vector<Field> numbers;
  std::vector<bool> plain;
  bool parametric = false;
  for (const auto* list : {&items, &center_items})
    for (const std::string& item : *list) {
      const std::optional<double> x = plain_number(item, s);
      if (!x) parametric = true;
      plain.push_back(x.has_value());
      numbers.push_back(x ? Field() : formula(item, s));
      (list == &items ? v : center).push_back(x.value_or(1));
    }
  if (!parametric) {
    add_numbers(*this, kind, s, v, at != std::string_view::npos ? &center : nullptr);
    return;
  }
  // The shape is checked now (placeholders for the values, which update() sets).
  if (kind == "sphere" && (v.size() != 1 || (at != std::string_view::npos && center.size() != 3)))
    throw InvalidArgument("--clip", s,
                          "a sphere needs one radius and, after '@', three centre numbers");
  if (kind == "box" && v.size() != 1 && v.size() != 6)
    throw InvalidArgument("--clip", s, "a box needs one positive half size or six numbers");
  if (kind == "plane" && v.size() != 4)
    throw InvalidArgument("--clip", s, "a plane needs nx,ny,nz,d");
  // Plain numbers are kept as constant fields, so that update() reads every number alike.
  for (std::size_t i = 0; i < numbers.size(); ++i)
    if (plain[i])
      numbers[i] = compile_field(i < items.size() ? items[i] : center_items[i - items.size()]);
  ClipFormula f{s, std::move(numbers), kind == "sphere" ? spheres.size() : planes.size(),
                kind == "sphere"};
  formulas.push_back(std::move(f));
  if (kind == "sphere") {
    spheres.push_back({});
  } else {
    planes.resize(planes.size() + adds);
  }
}

void Clip::update(const Field& field) {
  if (formulas.empty()) return;
  const auto& names = field.parameter_names();
  const auto& values = field.parameter_values();
  for (ClipFormula& f : formulas) {
    std::vector<double> v;
    for (Field& number : f.numbers) {
      for (const std::string& name : number.parameter_names()) {
        const int k = field.parameter_index(name);
        if (k < 0) {
          std::string have;
          for (const auto& n : names) have += (have.empty() ? "" : ", ") + n;
          throw InvalidArgument(
              "--clip", f.spec,
              fmt::format("'{}' is not a parameter of the surface{}", name,
                          have.empty() ? " (it has none)" : " (it has: " + have + ")"));
        }
        if (!std::isfinite(values[k]))
          throw InvalidArgument("--clip", f.spec,
                                fmt::format("the parameter '{}' has no value", name));
        number.set_parameter(name, values[k]);
      }
      Evaluator ev(number);
      const double x = ev.value(Vec3::Zero());
      if (!std::isfinite(x))
        throw InvalidArgument("--clip", f.spec,
                              fmt::format("'{}' is not a finite number at the parameters' "
                                          "values ({})",
                                          number.source(), x));
      v.push_back(x);
    }
    const std::string_view kind = std::string_view(f.spec).substr(0, f.spec.find(':'));
    const bool has_center = f.sphere && f.numbers.size() == 4;
    std::vector<double> center;
    if (has_center) center.assign(v.begin() + 1, v.end()), v.resize(1);
    Clip part;
    try {
      add_numbers(part, kind, f.spec, v, has_center ? &center : nullptr);
    } catch (const InvalidArgument& e) {
      std::string at;
      for (std::size_t k = 0; k < names.size() && at.size() < 200; ++k)
        at += fmt::format("{}{} = {:g}", at.empty() ? "" : ", ", names[k], values[k]);
      throw InvalidArgument(fmt::format("{} (at {})", e.what(), at));
    }
    if (f.sphere)
      spheres[f.first] = part.spheres.front();
    else
      std::copy(part.planes.begin(), part.planes.end(), planes.begin() + f.first);
  }
  check_extent();
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

bool Clip::contains(const Vec3& p, double tolerance) const {
  // value(p) <= tolerance, part by part and without the gradient: every stage asks this at
  // every point it moves.
  for (const auto& s : spheres)
    if ((p - s.center).norm() - s.radius > tolerance) return false;
  for (const auto& h : planes)
    if (h.normal.dot(p) - h.offset > tolerance) return false;
  return true;
}

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

bool Clip::ray_interval(const Vec3& o, const Vec3& d, double t_min, double& t0, double& t1) const {
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

std::vector<std::string> Clip::to_specs(bool values) const {
  // Parts a parametric spec sets are written as that spec.
  std::vector<bool> sphere_set(spheres.size()), plane_set(planes.size());
  for (const auto& f : formulas) {
    if (values) break;
    if (f.sphere)
      sphere_set[f.first] = true;
    else
      std::fill_n(plane_set.begin() + f.first, f.spec.starts_with("box") ? 6 : 1, true);
  }
  std::vector<std::string> out;
  for (std::size_t i = 0; i < spheres.size(); ++i) {
    if (sphere_set[i]) continue;
    const SphereClip& s = spheres[i];
    if (s.center.isZero())
      out.push_back(fmt::format("sphere:{}", s.radius));
    else
      out.push_back(
          fmt::format("sphere:{}@{},{},{}", s.radius, s.center.x(), s.center.y(), s.center.z()));
  }
  for (std::size_t i = 0; i < planes.size(); ++i) {
    if (plane_set[i]) continue;
    const HalfSpaceClip& h = planes[i];
    out.push_back(
        fmt::format("plane:{},{},{},{}", h.normal.x(), h.normal.y(), h.normal.z(), h.offset));
  }
  if (!values)
    for (const auto& f : formulas) out.push_back(f.spec);
  return out;
}

}  // namespace zeroset
