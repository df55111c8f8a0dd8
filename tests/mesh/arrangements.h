#pragma once
// Random arrangements of quadrics for the crossings tests (docs/meshing.md, "Crossings: the
// arrangements sweep"): products of 2 to 4 planes, spheres, cylinders, paraboloids and general
// quadrics in random positions in the unit ball, whose double curves are known exactly (where
// two factors vanish), and the checks of a mesh against them: points half an edge out along
// each sheet lie on the mesh, and the transversal double curves lie on edges shared by four
// triangles.
#include <fmt/core.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "mesh_distance.h"
#include "zeroset/mesh/mesh.h"

namespace zeroset::test {

// f(p) = pᵀAp + b·p + c.
struct Quadric {
  std::string kind;
  Mat3 a = Mat3::Zero();
  Vec3 b = Vec3::Zero();
  double c = 0;

  double value(const Vec3& p) const { return p.dot(a * p) + b.dot(p) + c; }
  Vec3 gradient(const Vec3& p) const { return 2 * (a * p) + b; }
  // Distance to the zero set, to first order.
  double distance(const Vec3& p) const {
    const double g = gradient(p).norm();
    return g > 0 ? std::abs(value(p)) / g : std::numeric_limits<double>::infinity();
  }
  std::string expression() const {
    const char* names[3] = {"x", "y", "z"};
    std::string out;
    auto term = [&](double k, const std::string& monomial) {
      if (k == 0) return;
      out += fmt::format("{}{:.17g}{}", out.empty() || k < 0 ? "" : "+", k,
                         monomial.empty() ? "" : "*" + monomial);
    };
    for (int i = 0; i < 3; ++i) {
      term(a(i, i), fmt::format("{}^2", names[i]));
      for (int j = i + 1; j < 3; ++j)
        term(a(i, j) + a(j, i), fmt::format("{}*{}", names[i], names[j]));
    }
    for (int i = 0; i < 3; ++i) term(b[i], names[i]);
    term(c, "");
    return out.empty() ? "0" : out;
  }
};

struct Arrangement {
  std::vector<Quadric> factors;
  std::string expression() const {
    std::string out;
    for (const Quadric& q : factors) out += (out.empty() ? "(" : "*(") + q.expression() + ")";
    return out;
  }
  std::string kinds() const {
    std::string out;
    for (const Quadric& q : factors) out += (out.empty() ? "" : " × ") + q.kind;
    return out;
  }
};

// A point of the double curve f = g = 0, reached by Newton's method from p (minimum-norm steps).
inline bool onto_double_curve(const Quadric& f, const Quadric& g, Vec3& p) {
  for (int it = 0; it < 40; ++it) {
    Eigen::Matrix<double, 2, 3> j;
    j.row(0) = f.gradient(p).transpose();
    j.row(1) = g.gradient(p).transpose();
    const Eigen::Vector2d r(f.value(p), g.value(p));
    if (r.norm() < 1e-13) return true;
    const Eigen::Matrix2d jj = j * j.transpose();
    if (!(std::abs(jj.determinant()) > 1e-14 * jj.squaredNorm())) return false;
    const Vec3 step = j.transpose() * jj.ldlt().solve(r);
    if (!(step.norm() < 0.2)) return false;
    p -= step;
  }
  return Eigen::Vector2d(f.value(p), g.value(p)).norm() < 1e-11;
}

inline bool onto_factor(const Quadric& f, Vec3& p) {
  for (int it = 0; it < 40; ++it) {
    const Vec3 g = f.gradient(p);
    const double v = f.value(p);
    if (std::abs(v) < 1e-14) return true;
    if (!(g.squaredNorm() > 0)) return false;
    const Vec3 step = v / g.squaredNorm() * g;
    if (!(step.norm() < 0.2)) return false;
    p -= step;
  }
  return std::abs(f.value(p)) < 1e-12;
}

// A random product of 2 to 4 factors, each meeting the ball of radius 0.7, with at least
// one double curve of length ≥ 0.5 inside the unit ball.
class ArrangementGenerator {
 public:
  explicit ArrangementGenerator(unsigned seed) : rng_(seed) {}

  Arrangement next() {
    for (;;) {
      Arrangement a;
      const int n = std::uniform_int_distribution<int>(2, 4)(rng_);
      for (int k = 0; k < n; ++k) a.factors.push_back(factor());
      if (has_double_curve(a)) return a;
    }
  }

 private:
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  Vec3 direction() {
    std::normal_distribution<double> n(0, 1);
    for (;;) {
      const Vec3 d(n(rng_), n(rng_), n(rng_));
      if (d.norm() > 1e-3) return d.normalized();
    }
  }
  Vec3 in_ball(double r) { return direction() * r * std::cbrt(uniform(0, 1)); }

  Quadric factor() {
    Quadric q;
    const int kind = std::uniform_int_distribution<int>(0, 4)(rng_);
    const Vec3 c = in_ball(0.6);
    if (kind == 0) {  // plane through c
      q.kind = "plane";
      q.b = direction();
      q.c = -q.b.dot(c);
    } else if (kind == 1) {  // sphere |p − c|² = r²
      q.kind = "sphere";
      const double r = uniform(0.3, 0.9);
      q.a = Mat3::Identity();
      q.b = -2 * c;
      q.c = c.squaredNorm() - r * r;
    } else if (kind == 2) {  // cylinder: distance r from the axis through c
      q.kind = "cylinder";
      const Vec3 axis = direction();
      const double r = uniform(0.2, 0.7);
      q.a = Mat3::Identity() - axis * axis.transpose();
      q.b = -2 * (q.a * c);
      q.c = c.dot(q.a * c) - r * r;
    } else if (kind == 3) {  // paraboloid k (u² + v²) = w in a random frame at c
      q.kind = "paraboloid";
      const Vec3 w = direction();
      const double k = uniform(0.5, 2.0);
      q.a = k * (Mat3::Identity() - w * w.transpose());
      q.b = -2 * (q.a * c) - w;
      q.c = c.dot(q.a * c) + w.dot(c);
    } else {  // a general quadric through c
      q.kind = "quadric";
      std::normal_distribution<double> n(0, 1);
      for (int i = 0; i < 3; ++i)
        for (int j = i; j < 3; ++j) q.a(i, j) = q.a(j, i) = n(rng_);
      q.b = Vec3(n(rng_), n(rng_), n(rng_));
      q.c = 0;
      q.c = -q.value(c);
    }
    return q;
  }

  bool has_double_curve(const Arrangement& a) {
    for (size_t i = 0; i < a.factors.size(); ++i)
      for (size_t j = i + 1; j < a.factors.size(); ++j)
        for (int s = 0; s < 200; ++s) {
          Vec3 p = in_ball(0.9);
          if (onto_double_curve(a.factors[i], a.factors[j], p) && p.norm() < 0.8) return true;
        }
    return false;
  }

  std::mt19937 rng_;
};

// A point of a double curve, with the two factors through it.
struct CurvePoint {
  Vec3 p;
  Vec3 tangent;
  int f, g;
};

// The double curves inside the ball of radius `radius`, traced in steps of `step` from
// random seeds.
inline std::vector<CurvePoint> double_curves(const Arrangement& a, double radius, double step,
                                             unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-radius, radius);
  std::vector<CurvePoint> out;
  for (int i = 0; i < static_cast<int>(a.factors.size()); ++i)
    for (int j = i + 1; j < static_cast<int>(a.factors.size()); ++j) {
      const Quadric &f = a.factors[static_cast<size_t>(i)], &g = a.factors[static_cast<size_t>(j)];
      std::map<std::array<long long, 3>, std::vector<Vec3>> seen;
      auto key = [&](const Vec3& p) {
        return std::array<long long, 3>{static_cast<long long>(std::floor(p.x() / step)),
                                        static_cast<long long>(std::floor(p.y() / step)),
                                        static_cast<long long>(std::floor(p.z() / step))};
      };
      auto near_seen = [&](const Vec3& p) {
        const auto k = key(p);
        for (long long x = k[0] - 1; x <= k[0] + 1; ++x)
          for (long long y = k[1] - 1; y <= k[1] + 1; ++y)
            for (long long z = k[2] - 1; z <= k[2] + 1; ++z) {
              const auto it = seen.find({x, y, z});
              if (it == seen.end()) continue;
              for (const Vec3& q : it->second)
                if ((q - p).norm() < 0.75 * step) return true;
            }
        return false;
      };
      for (int s = 0; s < 400; ++s) {
        Vec3 p(u(rng), u(rng), u(rng));
        if (!onto_double_curve(f, g, p) || !(p.norm() < radius) || near_seen(p)) continue;
        const Vec3 start = p;
        for (const double dir : {1.0, -1.0}) {
          Vec3 q = start;
          for (int k = 0; k < 100000; ++k) {
            const Vec3 t = f.gradient(q).cross(g.gradient(q));
            if (!(t.norm() > 1e-9 * f.gradient(q).norm() * g.gradient(q).norm())) break;
            if (k > 0 && near_seen(q)) break;  // closed, or met a traced piece
            seen[key(q)].push_back(q);
            out.push_back({q, t.normalized(), i, j});
            Vec3 next = q + dir * step * t.normalized();
            if (!onto_double_curve(f, g, next) || !(next.norm() < radius)) break;
            if ((next - q).norm() > 2 * step) break;
            q = next;
          }
        }
      }
    }
  return out;
}

// What a mesh shows of an arrangement's crossings.
struct ArrangementFigures {
  long long sheet_points = 0, sheet_on_mesh = 0;  // half an edge out along each sheet
  long long curve_points = 0, curve_on_four = 0;  // transversal double-curve points
  // The first few of each: where, how far from the mesh (or a four-triangle edge) in edge
  // lengths, and the sine of the angle between the sheets at the curve.
  struct Miss {
    Vec3 p;
    double distance, sin_angle;
  };
  std::vector<Miss> sheet_misses, curve_misses;
  double sheet_fraction() const {
    return sheet_points ? static_cast<double>(sheet_on_mesh) / static_cast<double>(sheet_points) : 1;
  }
  double curve_fraction() const {
    return curve_points ? static_cast<double>(curve_on_four) / static_cast<double>(curve_points) : 1;
  }
};

// Segments in BoxBins.
class SegmentBins : public BoxBins {
 public:
  SegmentBins(const std::vector<std::array<Vec3, 2>>& segments, double cell)
      : BoxBins(
            static_cast<std::uint32_t>(segments.size()),
            [&segments](std::uint32_t s) {
              return std::array<Vec3, 2>{segments[s][0].cwiseMin(segments[s][1]),
                                         segments[s][0].cwiseMax(segments[s][1])};
            },
            [&segments](std::uint32_t s, const Vec3& p) {
              const Vec3 &a = segments[s][0], ab = segments[s][1] - a;
              const double t = ab.squaredNorm() > 0
                                   ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0)
                                   : 0;
              return (a + t * ab - p).norm();
            },
            cell) {}
};

// Checks `mesh` (of the arrangement clipped to the ball of radius `radius`) against its
// double curves. Points within `keep_off` edge lengths of a third factor (a triple point) or
// of the clip are skipped, and so are the curve's points where the sheets meet at less than
// `min_angle_sin` (near a tangential meeting the sheets are closer than an edge).
struct ArrangementCheck {
  double radius = 1;
  double keep_off = 2;       // edge lengths
  double min_angle_sin = 0.25;
  double sheet_tolerance = 0.1;  // edge lengths
  double curve_tolerance = 0.1;  // edge lengths
  // Points within `skip_radius` of these are skipped (the places a mesh left as marching
  // cubes made them, to check every other crossing).
  std::vector<Vec3> skip_near;
  double skip_radius = 0;
};

inline ArrangementFigures check_arrangement(const Mesh& mesh, const Arrangement& a,
                                            const ArrangementCheck& check = {}) {
  ArrangementFigures out;
  if (mesh.triangles.empty()) return out;
  const double e = mean_edge(mesh);
  const TriangleBins triangles(mesh, e);
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> count;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) {
      const auto u = t[k], v = t[(k + 1) % 3];
      ++count[{std::min(u, v), std::max(u, v)}];
    }
  std::vector<std::array<Vec3, 2>> four;
  for (const auto& [edge, n] : count)
    if (n == 4) four.push_back({mesh.positions[edge.first], mesh.positions[edge.second]});
  const SegmentBins four_edges(four, e);
  auto away_from_others = [&](const Vec3& p, int f, int g, double d) {
    for (int k = 0; k < static_cast<int>(a.factors.size()); ++k)
      if (k != f && k != g && a.factors[static_cast<size_t>(k)].distance(p) < d) return false;
    for (const Vec3& q : check.skip_near)
      if ((q - p).norm() < check.skip_radius) return false;
    return check.radius - p.norm() >= d;
  };
  for (const CurvePoint& cp : double_curves(a, check.radius, 0.5 * e)) {
    const Quadric &f = a.factors[static_cast<size_t>(cp.f)], &g = a.factors[static_cast<size_t>(cp.g)];
    const Vec3 nf = f.gradient(cp.p).normalized(), ng = g.gradient(cp.p).normalized();
    if (nf.cross(ng).norm() < check.min_angle_sin) continue;
    if (!away_from_others(cp.p, cp.f, cp.g, check.keep_off * e)) continue;
    ++out.curve_points;
    const double sin_angle = nf.cross(ng).norm();
    if (const double d = four_edges.distance(cp.p); d <= check.curve_tolerance * e)
      ++out.curve_on_four;
    else if (out.curve_misses.size() < 8)
      out.curve_misses.push_back({cp.p, d / e, sin_angle});
    for (const auto& [sheet, normal] : {std::pair{&f, nf}, std::pair{&g, ng}})
      for (const double sign : {-1.0, 1.0}) {
        Vec3 q = cp.p + sign * 0.5 * e * normal.cross(cp.tangent).normalized();
        if (!onto_factor(*sheet, q) || !away_from_others(q, cp.f, cp.g, check.keep_off * e)) continue;
        ++out.sheet_points;
        if (const double d = triangles.distance(q); d <= check.sheet_tolerance * e)
          ++out.sheet_on_mesh;
        else if (out.sheet_misses.size() < 8)
          out.sheet_misses.push_back({q, d / e, sin_angle});
      }
  }
  return out;
}

}  // namespace zeroset::test
