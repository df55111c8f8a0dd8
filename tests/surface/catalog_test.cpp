#include "zeroset/surface/catalog.h"

#include <gtest/gtest.h>

#include <random>

#include "zeroset/error.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset {
namespace {

TEST(Catalog, HasTheSurfacesTheDesignNames) {
  for (const char* name : {"kummer", "cone", "planes", "sphere", "torus", "roman", "cayley",
                           "clebsch", "barth6", "whitney", "dingdong"})
    EXPECT_NE(find_catalog_entry(name), nullptr) << name;
  EXPECT_EQ(find_catalog_entry("no-such-surface"), nullptr);
}

TEST(Catalog, EveryEntryCompilesWithBoundedClipAndAllParameters) {
  for (const auto& e : catalog()) {
    Surface s = make_surface(e);
    EXPECT_TRUE(s.field.missing_parameters().empty()) << e.name;
    EXPECT_TRUE(s.clip.is_bounded()) << e.name;
    EXPECT_TRUE(s.field.is_polynomial()) << e.name;
    EXPECT_EQ(s.ranges.size(), s.field.parameter_names().size()) << e.name;
  }
}

TEST(Catalog, DegreesAreTheClassicalOnes) {
  auto degree = [](const char* n) { return make_surface(*find_catalog_entry(n)).field.degree(); };
  EXPECT_EQ(degree("kummer"), 4);
  EXPECT_EQ(degree("barth6"), 6);
  EXPECT_EQ(degree("cayley"), 3);
  EXPECT_EQ(degree("clebsch"), 3);
  EXPECT_EQ(degree("roman"), 4);
  EXPECT_EQ(degree("cone"), 2);
  EXPECT_EQ(degree("whitney"), 3);
  EXPECT_EQ(degree("dingdong"), 3);
}

void expect_singular(const Surface& s, const Vec3& p, const std::string& what) {
  Evaluator ev(s.field);
  Vec3 g;
  const double f = ev.value_gradient(p, g);
  EXPECT_LE(std::abs(f), 1e-9) << what << " at " << p.transpose();
  EXPECT_LE(g.norm(), 1e-7) << what << " at " << p.transpose();
}

TEST(Catalog, EveryListedSingularPointIsSingular) {
  for (const auto& e : catalog()) {
    Surface s = make_surface(e);
    for (const Vec3& p : s.singular_points()) expect_singular(s, p, e.name);
  }
}

TEST(Catalog, KummerHasSixteenNodesForEveryMuBetweenOneAndThree) {
  Surface s = make_surface(*find_catalog_entry("kummer"));
  for (double mu : {1.02, 1.2, 1.5, 2.0, 2.44, 2.9}) {
    s.field.set_parameter("mu", mu);
    const auto nodes = s.singular_points();
    EXPECT_EQ(nodes.size(), 16u) << "mu = " << mu;
    for (const Vec3& p : nodes) expect_singular(s, p, "kummer mu=" + std::to_string(mu));
    for (size_t i = 0; i < nodes.size(); ++i)
      for (size_t j = i + 1; j < nodes.size(); ++j)
        EXPECT_GT((nodes[i] - nodes[j]).norm(), 1e-3) << "distinct nodes, mu = " << mu;
  }
}

TEST(Catalog, KummerBelowOneHasOnlyItsFourRealNodes) {
  Surface s = make_surface(*find_catalog_entry("kummer"));
  s.field.set_parameter("mu", 0.6);
  const auto nodes = s.singular_points();
  EXPECT_EQ(nodes.size(), 4u);
  for (const Vec3& p : nodes) expect_singular(s, p, "kummer mu=0.6");
}

TEST(Catalog, KummerNodeOfTheIssueIsListed) {
  Surface s = make_surface(*find_catalog_entry("kummer"));
  s.field.set_parameter("mu", 1.5);
  const Vec3 want(1.0606601718, -0.3535533906, -0.5);
  double best = 1e9;
  for (const Vec3& p : s.singular_points()) best = std::min(best, (p - want).norm());
  EXPECT_LT(best, 1e-9);
}

TEST(Catalog, BarthSexticListsFiftyAffineNodes) {
  Surface s = make_surface(*find_catalog_entry("barth6"));
  const auto nodes = s.singular_points();
  EXPECT_EQ(nodes.size(), 50u);
  int at_one = 0, at_sqrt3 = 0;
  for (const Vec3& p : nodes) {
    if (std::abs(p.norm() - 1) < 1e-12) ++at_one;
    if (std::abs(p.norm() - std::sqrt(3.0)) < 1e-12) ++at_sqrt3;
  }
  EXPECT_EQ(at_one, 30);
  EXPECT_EQ(at_sqrt3, 20);
}

TEST(Catalog, CayleyCubicHasFourNodes) {
  EXPECT_EQ(make_surface(*find_catalog_entry("cayley")).singular_points().size(), 4u);
}

// The issue's acceptance: exact derivatives of every catalog surface against central
// differences at random points inside the clip.
TEST(Catalog, GradientsAndHessiansAgreeWithFiniteDifferences) {
  std::mt19937 rng(42);
  for (const auto& e : catalog()) {
    Surface s = make_surface(e);
    Evaluator ev(s.field);
    const Box3 b = s.bounds();
    std::uniform_real_distribution<double> u(0, 1);
    for (int trial = 0; trial < 50; ++trial) {
      const Vec3 p = b.lo + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(b.size());
      const FieldSample fs = ev.sample(p, Derivatives::kHessian);
      const double h = 1e-5 * std::max(1.0, p.norm());
      Vec3 g_fd;
      Mat3 h_fd;
      for (int k = 0; k < 3; ++k) {
        Vec3 d = Vec3::Zero();
        d[k] = h;
        g_fd[k] = (ev.value(p + d) - ev.value(p - d)) / (2 * h);
        Vec3 gp, gm;
        ev.value_gradient(p + d, gp);
        ev.value_gradient(p - d, gm);
        h_fd.col(k) = (gp - gm) / (2 * h);
      }
      const double gscale = std::max(1.0, fs.gradient.norm());
      const double hscale = std::max(1.0, fs.hessian.norm());
      EXPECT_LE((fs.gradient - g_fd).norm() / gscale, 1e-6) << e.name << " at " << p.transpose();
      EXPECT_LE((fs.hessian - h_fd).norm() / hscale, 1e-6) << e.name << " at " << p.transpose();
    }
  }
}

TEST(Catalog, PolynomialFormAgreesWithTheFieldOnEveryEntry) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  for (const auto& e : catalog()) {
    Surface s = make_surface(e);
    const Polynomial poly = s.field.polynomial();
    Evaluator ev(s.field);
    for (int t = 0; t < 100; ++t) {
      const Vec3 p(u(rng), u(rng), u(rng));
      const double f = ev.value(p);
      EXPECT_NEAR(poly.value(p), f, 1e-9 * std::max(1.0, std::abs(f))) << e.name;
    }
  }
}

}  // namespace
}  // namespace zeroset
