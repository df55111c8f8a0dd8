#include "zeroset/surface/catalog.h"

#include <array>
#include <cmath>

#include "zeroset/error.h"
#include "zeroset/expr/parse.h"

namespace zeroset {
namespace {

double param(const Field& f, std::string_view name) {
  const int i = f.parameter_index(name);
  ZS_ASSERT(i >= 0);
  return f.parameter_values()[i];
}

// Kummer family of the paper (§3.4), mu = ν². Its nodes, for any mu (Rösch–Ruhl–Saupe):
// with P = pqrs the product of the four tetrahedron planes, F = (3-mu)(|x|²-mu)² - (3mu-1)P.
//  - 12 nodes where |x|² = mu meets the 6 lines in which two of the planes intersect: the
//    line through tetrahedron vertices Va, Vb has its point nearest the origin at (Va+Vb)/2
//    (at distance 1), so it meets the sphere iff mu ≥ 1, at (Va+Vb)/2 ± sqrt(mu-1)·u.
//  - 4 nodes on the 3-fold axes: along t·V, F = (2t+1-mu)²(6t²-4t+1-mu), a double root at
//    t = (mu-1)/2.
// Each is a point where F and ∇F vanish; the tests check that for many mu.
std::vector<Vec3> kummer_nodes(const Field& f) {
  const double mu = param(f, "mu");
  const double s2 = std::sqrt(2.0);
  const std::array<Vec3, 4> v = {Vec3(0, -s2, 1), Vec3(0, s2, 1), Vec3(s2, 0, -1),
                                 Vec3(-s2, 0, -1)};
  std::vector<Vec3> out;
  if (std::abs(mu - 1.0 / 3.0) < 1e-12 || std::abs(mu - 3.0) < 1e-12) return out;  // degenerate
  for (const Vec3& vk : v) out.push_back(0.5 * (mu - 1) * vk);
  if (mu > 1) {
    const double u = std::sqrt(mu - 1);
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        const Vec3 mid = 0.5 * (v[a] + v[b]);
        const Vec3 dir = (v[b] - v[a]).normalized();
        out.push_back(mid + u * dir);
        out.push_back(mid - u * dir);
      }
  }
  return out;
}

// The clip of the paper's figure 1, a sphere holding every node (docs/singular.md, "The
// Kummer family"): radius max(3, 1.04·(mu - 1)), at least 1.2 times the farthest node's
// distance max(sqrt(mu), (sqrt(3)/2)·|mu - 1|) for every mu in the range; 3 (the whole bounded
// surface for mu < 1) up to mu ≈ 3.88, so the picture around the four planes at mu = 3 stays
// as it was. The language has no max: max(a, b) = (a + b + |a - b|)/2.
Clip kummer_clip() {
  Clip c;
  c.add("sphere:(3 + 1.04*(mu - 1) + abs(1.04*(mu - 1) - 3))/2");
  return c;
}

// Barth's sextic: 65 nodes in projective space, 50 of them affine for this equation: the 30
// points (±1,0,0) and cyclic permutations of (±φ/2, ±1/(2φ), ±1/2) on the unit sphere, and the
// 20 vertices of a dodecahedron, (±1,±1,±1) and cyclic permutations of (0, ±1/φ, ±φ), at
// radius √3. (The other 15 lie at infinity.)
std::vector<Vec3> barth_nodes(const Field&) {
  const double phi = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> out;
  auto cyclic = [&](double a, double b, double c) {
    out.emplace_back(a, b, c);
    out.emplace_back(c, a, b);
    out.emplace_back(b, c, a);
  };
  for (int k = 0; k < 3; ++k)
    for (double s : {-1.0, 1.0}) {
      Vec3 p = Vec3::Zero();
      p[k] = s;
      out.push_back(p);
    }
  for (double sa : {-1.0, 1.0})
    for (double sb : {-1.0, 1.0})
      for (double sc : {-1.0, 1.0}) cyclic(sa * phi / 2, sb / (2 * phi), sc * 0.5);
  for (double sa : {-1.0, 1.0})
    for (double sb : {-1.0, 1.0})
      for (double sc : {-1.0, 1.0}) out.emplace_back(sa, sb, sc);
  for (double sa : {-1.0, 1.0})
    for (double sb : {-1.0, 1.0}) cyclic(0.0, sa / phi, sb * phi);
  return out;
}

Camera cam(double az, double el, double fov = 30) {
  Camera c;
  c.azimuth_deg = az;
  c.elevation_deg = el;
  c.fov_deg = fov;
  return c;
}

Clip planes_clip(std::initializer_list<const char*> specs) {
  Clip c;
  for (const char* s : specs) c.add(s);
  return c;
}

std::vector<CatalogEntry> build_catalog() {
  std::vector<CatalogEntry> c;
  c.push_back({
      "kummer",
      "Kummer quartic family (Rösch–Ruhl–Saupe 1997)",
      "p = 1 - z - sqrt(2)*x; q = 1 - z + sqrt(2)*x\n"
      "r = 1 + z + sqrt(2)*y; s = 1 + z - sqrt(2)*y\n"
      "(3 - mu)*(x^2 + y^2 + z^2 - mu)^2 - (3*mu - 1)*p*q*r*s",
      "Quartics with tetrahedral symmetry, mu = nu^2: a double sphere at mu = 1/3, four real "
      "nodes below mu = 1, Steiner's Roman surface at mu = 1, 16 real nodes above it, four "
      "planes at mu = 3, approaching a tetrahedron as mu grows. The clip sphere grows with mu "
      "to hold every node.",
      {{"mu", 1.5, 1.0 / 3.0 + 0.01, 1.28e6}},
      kummer_clip(),
      cam(30, 20),
      kummer_nodes,
  });
  c.push_back({
      "cone",
      "Cone with its cusp (paper figure 3)",
      "x^2 + y^2 - z^2",
      "A circular cone clipped by the planes z = 1 and z = 0, the second through the cusp at "
      "the origin (and by a sphere of radius 1.5 that only bounds the volume).",
      {},
      planes_clip({"plane:0,0,1,1", "plane:0,0,-1,0", "sphere:1.5"}),
      cam(30, 25),
      [](const Field&) { return std::vector<Vec3>{Vec3::Zero()}; },
  });
  c.push_back({
      "planes",
      "Two orthogonal planes (paper figure 4)",
      "(x - a) * (y + a)",
      "Planes x = a and y = -a crossing at right angles in a line parallel to z; moving a "
      "moves the line. Every point of the line is singular.",
      {{"a", 0.0, -0.5, 0.5}},
      Clip::sphere(1),
      cam(35, 25),
      {},
  });
  c.push_back({"sphere",
               "Unit sphere",
               "x^2 + y^2 + z^2 - 1",
               "Smooth and closed.",
               {},
               Clip::sphere(1.5),
               cam(30, 20),
               {}});
  c.push_back({
      "torus",
      "Ring torus",
      "(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
      "Major radius R around the z axis, tube radius r; smooth and closed for r < R.",
      {{"R", 1.0, 0.2, 2.0}, {"r", 0.4, 0.05, 1.0}},
      Clip::sphere(1.6),
      cam(30, 35),
      {},
  });
  c.push_back({
      "roman",
      "Steiner's Roman surface",
      "x^2*y^2 + y^2*z^2 + z^2*x^2 - x*y*z",
      "Three double lines along the axes meet in a triple point at the origin and end in six "
      "pinch points (±1/2 on each axis). The equation also contains the whole axes.",
      {},
      Clip::sphere(0.6),
      cam(35, 25),
      [](const Field&) {
        std::vector<Vec3> out{Vec3::Zero()};
        for (int k = 0; k < 3; ++k)
          for (double s : {-0.5, 0.5}) {
            Vec3 p = Vec3::Zero();
            p[k] = s;
            out.push_back(p);
          }
        return out;
      },
  });
  c.push_back({
      "cayley",
      "Cayley's nodal cubic",
      "4*(x^2 + y^2 + z^2) + 16*x*y*z - 1",
      "The cubic surface with the most nodes: four, at the vertices of a tetrahedron.",
      {},
      Clip::sphere(1.5),
      cam(30, 20),
      [](const Field&) {
        return std::vector<Vec3>{Vec3(-0.5, -0.5, -0.5), Vec3(0.5, 0.5, -0.5), Vec3(0.5, -0.5, 0.5),
                                 Vec3(-0.5, 0.5, 0.5)};
      },
  });
  c.push_back({
      "clebsch",
      "Clebsch diagonal cubic",
      "81*(x^3 + y^3 + z^3) - 189*(x^2*y + x^2*z + y^2*x + y^2*z + z^2*x + z^2*y)"
      " + 54*x*y*z + 126*(x*y + x*z + y*z) - 9*(x^2 + y^2 + z^2) - 9*(x + y + z) + 1",
      "Smooth cubic whose 27 lines are all real.",
      {},
      Clip::sphere(1.2),
      cam(30, 20),
      {},
  });
  c.push_back({
      "barth6",
      "Barth's sextic",
      "phi = (1 + sqrt(5))/2\n"
      "4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - (1 + 2*phi)*(x^2 + y^2 + z^2 - "
      "1)^2",
      "The sextic with 65 nodes, the most known for degree 6; 50 of them are affine here.",
      {},
      Clip::sphere(1.8),
      cam(30, 25),
      barth_nodes,
  });
  c.push_back({
      "whitney",
      "Whitney umbrella",
      "x^2 - y^2*z",
      "Singular along the z axis, with a pinch point at the origin; the negative z axis is "
      "the umbrella's handle.",
      {},
      Clip::sphere(1),
      cam(40, 25),
      [](const Field&) { return std::vector<Vec3>{Vec3::Zero()}; },
  });
  c.push_back({
      "dingdong",
      "Ding-dong surface",
      "x^2 + y^2 + z^3 - z^2",
      "x² + y² = (1 - z)z²: a bell with a node at the origin.",
      {},
      Clip::sphere(1.5, Vec3(0, 0, 0.2)),
      cam(30, 15),
      [](const Field&) { return std::vector<Vec3>{Vec3::Zero()}; },
  });
  return c;
}

}  // namespace

const std::vector<CatalogEntry>& catalog() {
  static const std::vector<CatalogEntry> entries = build_catalog();
  return entries;
}

const CatalogEntry* find_catalog_entry(std::string_view name) {
  for (const auto& e : catalog())
    if (e.name == name) return &e;
  return nullptr;
}

Surface make_surface(const CatalogEntry& e) {
  Surface s;
  s.name = e.name;
  s.title = e.title;
  s.field = compile_field(e.equation);
  for (const auto& p : e.params) {
    s.field.set_parameter(p.name, p.value);
    s.ranges.push_back({p.name, p.min, p.max});
  }
  s.clip = e.clip;
  s.clip.update(s.field);
  s.camera = e.camera;
  s.singular_points_fn = e.singular_points;
  return s;
}

}  // namespace zeroset
