// Meshes with true crossings along singular curves: the curve lies on the mesh, the sheets
// reach it from every side, its edges are shared by the triangles of all sheets, and the
// improved mesh is at rest, oriented and on F = 0 away from the singular set.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include <Eigen/Eigenvalues>

#include "mesh_distance.h"
#include "mesh_test_support.h"
#include "zeroset/mesh/crossings.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"
#include "zeroset/mesh/remesh.h"
#include "zeroset/surface/analysis.h"

namespace zeroset {
namespace {

using test::mean_edge;
using test::TriangleBins;

// The two directions of the sheets through a crossing point p (tangent t): the null lines of
// the Hessian restricted to the plane normal to t.
std::array<Vec3, 2> sheet_directions(Evaluator& ev, const Vec3& p, const Vec3& t) {
  const Mat3 h = ev.sample(p, Derivatives::kHessian).hessian;
  Vec3 u = t.unitOrthogonal(), v = t.cross(u).normalized();
  Eigen::Matrix2d q;
  q << u.dot(h * u), u.dot(h * v), v.dot(h * u), v.dot(h * v);
  // q = λ₀ e₀e₀ᵀ + λ₁ e₁e₁ᵀ with λ₀ < 0 < λ₁ vanishes along √λ₁ e₀ ± √−λ₀ e₁.
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(q);
  const Eigen::Vector2d l = es.eigenvalues();
  const Eigen::Matrix2d vec = es.eigenvectors();
  std::array<Vec3, 2> out;
  for (int k = 0; k < 2; ++k) {
    const Eigen::Vector2d d = std::sqrt(std::max(0.0, l[1])) * vec.col(0) +
                              (k ? 1.0 : -1.0) * std::sqrt(std::max(0.0, -l[0])) * vec.col(1);
    out[static_cast<size_t>(k)] = (d[0] * u + d[1] * v).normalized();
  }
  return out;
}

struct Expect {
  int min_crossing_curves = 1;
  bool triple_line = false;  // edges on the curve may carry six triangles
  // Triangles facing against ∇F allowed away from the singular set: a check that does not
  // hold yet on every surface (docs/meshing.md, "Crossings": limits).
  int max_flipped = 0;
  // How far the independently traced curve may be from the mesh, in mean edge lengths; 0:
  // 1e-6 of the scene radius (straight curves lie on the mesh's chords exactly; a curved one
  // is a chord's sagitta away between the mesh's vertices).
  double curve_tolerance_edges = 0;
  // The improver comes to rest within this many steps (0: within its default limit).
  int max_steps = 0;
  // The paper's improver; false: the remesher (the default of `zeroset mesh`).
  bool paper = true;
};

void check_crossing_mesh(const Surface& s, int cells, const Expect& expect = {}) {
  SCOPED_TRACE(s.label() + " at " + std::to_string(cells) + " cells, " +
               (expect.paper ? "paper's improver" : "remesher"));
  PolygonizeStats ps;
  Mesh m = polygonize(s, {.cells = cells}, &ps);
  const CrossingStats cs = mesh_crossings(m, s, ps.cell_size);
  ASSERT_TRUE(cs.failure.empty()) << cs.failure;
  ASSERT_GE(cs.crossing_curves, expect.min_crossing_curves);
  if (expect.paper) {
    const ImproveStats st = improve_mesh(m, s);
    EXPECT_TRUE(st.converged) << "not at rest after " << st.steps << " steps";
    if (expect.max_steps > 0) {
      EXPECT_LE(st.steps, expect.max_steps);
    }
  } else {
    const RemeshStats st = remesh(m, s);
    EXPECT_TRUE(st.converged) << "not at rest after " << st.iterations << " iterations";
    if (expect.max_steps > 0) {
      EXPECT_LE(st.iterations, expect.max_steps);
    }
  }
  const double e = mean_edge(m);
  const double radius = s.scene_radius();
  const TriangleBins bins(m, e);

  // The curve as found independently (its own spacing) lies on the mesh.
  const SingularSet set = find_singular_set(s);
  // Where sheets meet at a special point there is no "out along each sheet"; towards a pinch
  // point the two sheets close like a book and the surface folds sharply within a few edge
  // lengths of it (docs/meshing.md, "Crossings": limits).
  auto near_special = [&](const Vec3& p) {
    for (const SingularPoint& q : set.points) {
      const double r = q.kind == SingularPointKind::kPinch ? 4.5 * ps.cell_size : 2 * e;
      if ((q.position - p).norm() < r) return true;
    }
    return false;
  };
  Evaluator ev(s.field);
  int crossing = 0;
  for (const SingularCurve& c : set.curves) {
    if (c.kind != CurveKind::kCrossing) continue;
    ++crossing;
    for (size_t i = 0; i < c.points.size(); ++i) {
      const Vec3& p = c.points[i];
      const double tolerance =
          expect.curve_tolerance_edges > 0 ? expect.curve_tolerance_edges * e : 1e-6 * radius;
      ASSERT_LE(bins.distance(p), tolerance) << "curve point " << p.transpose();
      if (i == 0 || i + 1 == c.points.size()) continue;
      // Half an edge out along each sheet, projected onto F = 0: on the mesh.
      const Vec3 t = (c.points[i + 1] - c.points[i - 1]).normalized();
      if (near_special(p)) continue;
      for (const Vec3& d : sheet_directions(ev, p, t))
        for (double sign : {-1.0, 1.0}) {
          Vec3 q = p + sign * 0.5 * e * d;
          ASSERT_TRUE(project_onto_surface(ev, q, 1e-12 * radius, 0.25 * e)) << q.transpose();
          if (!s.clip.contains(q) || std::abs(s.clip.value(q)) < e) continue;
          EXPECT_LE(bins.distance(q), 0.05 * e) << "sheet point " << q.transpose();
        }
    }
  }
  EXPECT_GE(crossing, expect.min_crossing_curves);

  // Edges of the mesh's curves are shared by the triangles of all sheets through them.
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> count;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const auto a = t[k], b = t[(k + 1) % 3];
      ++count[{std::min(a, b), std::max(a, b)}];
    }
  long long curve_edges = 0, four = 0;
  for (const MeshCurve& c : m.curves) {
    if (c.kind != CurveKind::kCrossing) continue;
    for (size_t k = 0; k + 1 < c.vertices.size(); ++k) {
      const auto a = c.vertices[k], b = c.vertices[k + 1];
      const Vec3 mid = 0.5 * (m.positions[a] + m.positions[b]);
      if (!s.clip.is_empty_spec() && std::abs(s.clip.value(mid)) < 2 * e) continue;  // clip end
      if (near_special(mid)) continue;
      const int n = count[{std::min(a, b), std::max(a, b)}];
      ++curve_edges;
      if (n == 4 || (expect.triple_line && n == 6))
        ++four;
      else
        ADD_FAILURE() << "curve edge at " << mid.transpose() << " has " << n << " triangles";
    }
  }
  EXPECT_GT(curve_edges, 0);
  EXPECT_EQ(four, curve_edges);

  // Away from the singular set: oriented along ∇F and on F = 0; quality overall.
  double worst = 0;
  for (size_t v = 0; v < m.positions.size(); ++v) {
    const Vec3& p = m.positions[v];
    if (set.distance(p) < 2 * e || near_special(p)) continue;
    const FieldSample fs = ev.sample(p, Derivatives::kHessian);
    if (fs.gradient.norm() > 0) worst = std::max(worst, std::abs(fs.value) / fs.gradient.norm());
  }
  EXPECT_LE(worst, 1e-9);
  int flipped = 0;
  for (const auto& t : m.triangles) {
    const Vec3 c = (m.positions[t[0]] + m.positions[t[1]] + m.positions[t[2]]) / 3;
    if (set.distance(c) < 2 * e || near_special(c)) continue;
    const Vec3 n =
        (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
    if (n.dot(ev.sample(c, Derivatives::kHessian).gradient) < 0) ++flipped;
  }
  EXPECT_LE(flipped, expect.max_flipped);
  const MeshQuality q = measure_quality(m, s);
  EXPECT_LE(q.percent_below_30, 10.0);
}

TEST(Crossings, RomanSurface) {
  const Surface s = test::catalog_surface("roman");
  check_crossing_mesh(s, 128, {.min_crossing_curves = 3});
  check_crossing_mesh(s, 96, {.min_crossing_curves = 3});
}

TEST(Crossings, WhitneyUmbrella) {
  const Surface s = test::catalog_surface("whitney");
  check_crossing_mesh(s, 128);
  check_crossing_mesh(s, 96);
}

// Four planes: six double lines through four triple points, each sheet cut into narrow (60°)
// and wide sectors around them.
TEST(Crossings, KummerFourPlanes) {
  const Surface s = test::kummer(3, 3);
  check_crossing_mesh(s, 64, {.min_crossing_curves = 6});
  // At 96 cells one sliver (area 0.002 e², 2.1 edge lengths from a line) can end up turned
  // over, depending on the last bits of the arithmetic (it does in some builds, not in
  // others): a limit named in docs/meshing.md, "Crossings".
  // The wide flat sectors relax slowly without the springs' inertia (docs/meshing.md,
  // "Crossings": 291 steps at 96 cells; 192 with it).
  check_crossing_mesh(s, 96, {.min_crossing_curves = 6, .max_flipped = 1, .max_steps = 240});
}

TEST(Crossings, SphereCrossingACylinderAlongTwoCircles) {
  // x² + y² + z² = 1 and x² + y² = 0.64 meet in the circles z = ±0.6.
  const Surface s = test::equation("(x^2 + y^2 + z^2 - 1) * (x^2 + y^2 - 0.64)", Clip::sphere(1.3));
  check_crossing_mesh(s, 64, {.min_crossing_curves = 2, .curve_tolerance_edges = 0.02});
}

TEST(Crossings, TwoPlanes) {
  Surface s = test::catalog_surface("planes");
  s.field.set_parameter("a", 0.3);
  check_crossing_mesh(s, 128);
  check_crossing_mesh(s, 96);
}

// The same checks with the remesher, the default improver of `zeroset mesh`. On Roman's
// surface 5 to 6 cells from its pinch points, where the two sheets are about half an edge
// apart, the remesher's own relaxation strayed up to 0.4 edge lengths from a sheet and left
// triangles against ∇F; there the spring–mass improver now places the vertices
// (docs/meshing.md, "Crossings").
TEST(Crossings, RemesherKeepsEveryCrossing) {
  for (const int cells : {128, 96}) {
    check_crossing_mesh(test::catalog_surface("roman"), cells,
                        {.min_crossing_curves = 3, .paper = false});
    check_crossing_mesh(test::catalog_surface("whitney"), cells, {.paper = false});
    check_crossing_mesh(test::kummer(3, 3), cells, {.min_crossing_curves = 6, .paper = false});
    Surface planes = test::catalog_surface("planes");
    planes.field.set_parameter("a", 0.3);
    check_crossing_mesh(planes, cells, {.paper = false});
  }
}

// Plücker's conoid z (x² + y²) = 2xy: the sheets z = sin 2θ are ruled by horizontal lines
// through the z axis, which they cross along |z| < 1, pinch points at z = ±1, whiskers beyond.
// The rim of the tube's cut is one closed chain that runs up and down the double line twice,
// once along each half-sheet. At 128 cells the sheets are a quarter of an edge apart 5.3
// cells from a pinch point, where the remesher leaves the mesh to the paper's improver
// (docs/meshing.md, "Crossings": limits).
TEST(Crossings, PluckerConoid) {
  const Surface s = test::equation("z*(x^2+y^2) - 2*x*y", Clip::sphere(1.5));
  for (const int cells : {64, 96})
    for (const bool paper : {false, true}) check_crossing_mesh(s, cells, {.paper = paper});
  check_crossing_mesh(s, 128, {.paper = false});
}

// The cross-cap 4x²(x² + y² + z² + z) + y²(y² + z² − 1) = 0: a double segment from a pinch point
// at the origin to one at z = 1, the isolated z axis below; and a torus crossing its equatorial
// plane along two circles (curved curves: a chord's sagitta from the mesh between vertices).
// The clip leaves the plane a ring 5 cells wide outside the torus: at 2 cells (a clip radius of
// 1.5) the ring is lost (docs/meshing.md, "Crossings": limits).
TEST(Crossings, CrossCapAndTorusThroughAPlaneWithTheRemesher) {
  const Surface cap = test::equation("4*x^2*(x^2+y^2+z^2+z) + y^2*(y^2+z^2-1)", Clip::sphere(1.5));
  const Surface torus =
      test::equation("((x^2+y^2+z^2+0.84)^2 - 4*(x^2+y^2)) * z", Clip::sphere(1.7));
  for (const int cells : {64, 96}) {
    check_crossing_mesh(cap, cells, {.paper = false});
    check_crossing_mesh(torus, cells,
                        {.min_crossing_curves = 2, .curve_tolerance_edges = 0.02, .paper = false});
  }
}

}  // namespace
}  // namespace zeroset
