// Carrying a mesh along a parameter change: it stays on F = 0 and unflipped while the surface
// only moves, and refuses when the singular set changes.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <string>

#include "mesh_test_support.h"
#include "zeroset/error.h"
#include "zeroset/mesh/carry.h"
#include "zeroset/mesh/crossings.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"

namespace zeroset {
namespace {

Surface with_parameter(Surface s, const std::string& name, double value) {
  s.field.set_parameter(name, value);
  s.clip.update(s.field);
  return s;
}

// One thread throughout: on a busy machine an OpenMP team spins at every barrier while one of
// its threads waits for a core, and these meshes are small.
Mesh improved_mesh(const Surface& s, int cells) {
  Mesh m = polygonize(s, {.cells = cells, .threads = 1});
  improve_mesh(m, s, {.max_steps = 60, .threads = 1});
  return m;
}

// Measured independently of the carrier: the mesh lies on F = 0 and no triangle away from
// the singular points faces against ∇F. Returns how many known singular points are vertices.
int expect_on_surface(const Mesh& m, const Surface& s, const std::string& where) {
  const MeshQuality q = measure_quality(m, s, {.threads = 1});
  EXPECT_EQ(q.flipped_triangles, 0u) << where;
  EXPECT_LT(q.max_residual, 1e-9 * q.mean_edge_length) << where;
  EXPECT_EQ(q.zero_area_triangles, 0u) << where;
  EXPECT_EQ(q.undefined_vertices, 0u) << where;
  return static_cast<int>(std::count_if(q.singular_point_distance.begin(),
                                        q.singular_point_distance.end(),
                                        [](double d) { return d < 1e-9; }));
}

TEST(Carry, KummerFollowsASweepOfMu) {
  // As the viewer does: carry at every step, rebuild where carrying refuses. The central part
  // grows from about one edge across to several, so somewhere its few triangles no longer
  // suffice and a rebuild is due; every other step is carried.
  Surface s = with_parameter(test::catalog_surface("kummer"), "mu", 1.2);
  Mesh m = improved_mesh(s, 24);
  int nodes = expect_on_surface(m, s, "start");
  EXPECT_EQ(nodes, 16);
  int carried = 0;
  for (int i = 1; i <= 40; ++i) {
    const Surface next = with_parameter(s, "mu", 1.2 + 0.8 * i / 40);
    const std::string where = "step " + std::to_string(i);
    CarryResult r = carry_mesh(m, s, next, {.threads = 1});
    if (r.carried()) {
      ++carried;
      EXPECT_EQ(r.mesh.vertex_count(), m.vertex_count()) << where;
      EXPECT_GE(r.node_vertices, nodes) << where;
      m = std::move(r.mesh);
      // Node vertices stay node vertices (the improver steps may catch one a rebuild missed).
      const int held = expect_on_surface(m, next, where);
      EXPECT_GE(held, nodes) << where;
      nodes = held;
    } else {
      // Only quality may fail here: the singular set keeps its sixteen nodes.
      EXPECT_NE(r.failure, CarryFailure::kSingularSet) << where << ": " << r.reason;
      EXPECT_TRUE(r.mesh.empty());
      m = improved_mesh(next, 24);
      nodes = expect_on_surface(m, next, where);
    }
    s = next;
  }
  EXPECT_GE(carried, 36);
}

TEST(Carry, SphereRadiusWithAClipCurve) {
  // The clip plane cuts the sphere: the boundary vertices slide onto the new clip curve.
  Clip clip = Clip::sphere(3);
  clip.add("plane:0,0,1,0.3");
  Surface s = test::equation("x^2 + y^2 + z^2 - r^2", clip);
  s = with_parameter(s, "r", 1);
  Mesh m = improved_mesh(s, 16);
  for (int i = 1; i <= 10; ++i) {
    const Surface next = with_parameter(s, "r", 1 + 0.5 * i / 10);
    CarryResult r = carry_mesh(m, s, next, {.threads = 1});
    ASSERT_TRUE(r.carried()) << "step " << i << ": " << r.reason;
    expect_on_surface(r.mesh, next, "step " + std::to_string(i));
    const MeshQuality q = measure_quality(r.mesh, next, {.threads = 1});
    EXPECT_GT(q.boundary_vertices, 0u);
    EXPECT_LT(q.max_boundary_clip_value, 1e-9);
    m = std::move(r.mesh);
    s = next;
  }
}

TEST(Carry, ACrossingCurveMovesWithItsSheets) {
  // Two planes z − c = ±x cross on the line x = 0, z = c: its vertices (mesh_crossings makes
  // them shared by the four sheets) go back onto the line as c moves.
  Surface s = test::equation("(z - c)^2 - x^2", Clip::sphere(1));
  s = with_parameter(s, "c", 0);
  PolygonizeStats ps;
  Mesh m = polygonize(s, {.cells = 16, .threads = 1}, &ps);
  ASSERT_GT(mesh_crossings(m, s, ps.cell_size).crossing_curves, 0);
  improve_mesh(m, s, {.max_steps = 30, .threads = 1});
  ASSERT_FALSE(m.curves.empty());
  for (int i = 1; i <= 8; ++i) {
    const double c = 0.2 * i / 8;
    const Surface next = with_parameter(s, "c", c);
    CarryResult r = carry_mesh(m, s, next, {.threads = 1});
    ASSERT_TRUE(r.carried()) << "c = " << c << ": " << r.reason;
    ASSERT_EQ(r.mesh.curves.size(), m.curves.size());
    for (const MeshCurve& curve : r.mesh.curves)
      for (std::uint32_t v : curve.vertices) {
        const Vec3& p = r.mesh.positions[v];
        EXPECT_LT(std::abs(p.x()), 1e-9) << "c = " << c;
        EXPECT_LT(std::abs(p.z() - c), 1e-9) << "c = " << c;
      }
    m = std::move(r.mesh);
    s = next;
  }
}

TEST(Carry, KummerRefusesWhereNodesAppear) {
  // Below mu = 1 four real nodes, above it sixteen: the mesh must be rebuilt there.
  Surface s = with_parameter(test::catalog_surface("kummer"), "mu", 0.9);
  Mesh m = improved_mesh(s, 24);
  const Surface next = with_parameter(s, "mu", 1.1);
  const CarryResult r = carry_mesh(m, s, next, {.threads = 1});
  EXPECT_EQ(r.failure, CarryFailure::kSingularSet);
  EXPECT_NE(r.reason.find("4 → 16"), std::string::npos) << r.reason;
  EXPECT_TRUE(r.mesh.empty());
}

TEST(Carry, TorusChangingTopologyIsRebuilt) {
  // The ring torus (R > r) becomes a spindle torus (R < r) with two nodes on the axis; no
  // known singular points: the singular set is searched.
  Surface s = test::equation("(x^2 + y^2 + z^2 + R^2 - 1)^2 - 4*R^2*(x^2 + y^2)", Clip::sphere(3));
  s = with_parameter(s, "R", 1.3);
  Mesh m = improved_mesh(s, 24);
  int carried = 0, refused = 0;
  // As the viewer does: each carry hands the next one the singular set it found, so only the
  // new surface is searched; the change must still be seen.
  std::optional<CarrySingularSet> singular;
  for (int i = 1; i <= 11 && refused == 0; ++i) {
    // R = 1 itself (a node at the origin) is stepped over.
    const Surface next = with_parameter(s, "R", 1.3 - 0.6 * i / 11);
    CarryResult r = carry_mesh(m, s, next, {.threads = 1, .from_singular = singular});
    ASSERT_TRUE(r.singular.has_value()) << r.reason;
    if (!r.carried()) {
      ++refused;
      EXPECT_LT(next.field.parameter_values()[0], 1.0) << r.reason;
      EXPECT_EQ(r.failure, CarryFailure::kSingularSet) << r.reason;
      EXPECT_EQ(r.singular->points.size(), 2u) << r.reason;  // the spindle's two nodes
      break;
    }
    ++carried;
    EXPECT_TRUE(r.singular->points.empty());
    expect_on_surface(r.mesh, next, "R step " + std::to_string(i));
    if (i == 2) {
      // Handing in the set the first carry found changes nothing but the time.
      const CarryResult searched = carry_mesh(m, s, next, {.threads = 1});
      ASSERT_TRUE(searched.carried()) << searched.reason;
      EXPECT_EQ(searched.mesh.positions, r.mesh.positions);
    }
    singular = std::move(r.singular);
    m = std::move(r.mesh);
    s = next;
  }
  EXPECT_GT(carried, 0);
  EXPECT_EQ(refused, 1);
}

TEST(Carry, AnotherEquationIsNotCarried) {
  const Surface a = test::equation("x^2 + y^2 + z^2 - 1", Clip::sphere(2));
  const Surface b = test::equation("x^2 + y^2 + 2*z^2 - 1", Clip::sphere(2));
  const Mesh m = improved_mesh(a, 12);
  EXPECT_EQ(carry_mesh(m, a, b).failure, CarryFailure::kEquation);
}

TEST(Carry, ASphereGrowingOutOfItsClipIsRebuilt) {
  // The first-order move of a sphere's radius is exact, even for a jump; but at r = 2 the
  // clip sphere of radius 1.5 cuts the sphere, and the mesh has no boundary there.
  Surface s = test::equation("x^2 + y^2 + z^2 - r^2", Clip::sphere(1.5));
  s = with_parameter(s, "r", 1);
  const Mesh m = improved_mesh(s, 16);
  const CarryResult r = carry_mesh(m, s, with_parameter(s, "r", 2));
  EXPECT_EQ(r.failure, CarryFailure::kClip) << r.reason;
  // A jump that stays inside is carried.
  EXPECT_TRUE(carry_mesh(m, s, with_parameter(s, "r", 1.4)).carried());
}

TEST(Carry, ATwistedSheetIsNotFollowedByNewtonAlone) {
  // F = z cos q − x sin q: the plane turns about the y axis. Turned through a right angle in
  // one go, no vertex is near where its first-order move leads: never carried.
  Surface s = test::equation("z*cos(q) - x*sin(q)", Clip::sphere(1));
  s = with_parameter(s, "q", 0);
  const Mesh m = improved_mesh(s, 16);
  const CarryResult r = carry_mesh(m, s, with_parameter(s, "q", 1.6));
  EXPECT_FALSE(r.carried());
  EXPECT_FALSE(r.reason.empty());
}

TEST(Carry, RejectsBadOptions) {
  Surface s = test::equation("x^2 + y^2 + z^2 - r^2", Clip::sphere(3));
  s = with_parameter(s, "r", 1);
  const Mesh m = improved_mesh(s, 8);
  EXPECT_THROW(carry_mesh(m, s, s, {.improve_steps = -1}), InvalidArgument);
  EXPECT_THROW(carry_mesh(m, s, s, {.max_move_edges = 0}), InvalidArgument);
  Mesh broken = m;
  broken.triangles.push_back({0, 1, 100000});
  EXPECT_THROW(carry_mesh(broken, s, s), InvalidArgument);
}

}  // namespace
}  // namespace zeroset
