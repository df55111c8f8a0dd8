#include "zeroset/expr/polynomial.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "surfaces.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"

namespace zeroset {
namespace {

/// Σ |c|·|x|^i·|y|^j·|z|^k: the size of the terms that cancel in p(point), the natural scale
/// for its rounding error.
double term_scale(const Polynomial& p, const Vec3& point) {
  double s = 0;
  for (const Monomial& m : p.terms())
    s += std::abs(m.c) * std::pow(std::abs(point.x()), m.i) * std::pow(std::abs(point.y()), m.j) *
         std::pow(std::abs(point.z()), m.k);
  return s;
}

double horner(const std::vector<double>& a, double t) {
  double v = 0;
  for (auto it = a.rbegin(); it != a.rend(); ++it) v = v * t + *it;
  return v;
}

TEST(Polynomial, ExpansionAgreesWithFieldAtRandomPoints) {
  for (const auto& surface : test::polynomial_surfaces()) {
    SCOPED_TRACE(surface.source);
    const Field f = test::compile(surface);
    const Polynomial p = f.polynomial();
    EXPECT_EQ(p.degree(), f.degree());
    Evaluator ev(f);
    for (const Vec3& x : test::random_points(50, 1.5, 21)) {
      const double scale = std::max(1.0, term_scale(p, x));
      EXPECT_NEAR(p.value(x), ev.value(x), 1e-13 * scale) << x.transpose();
    }
  }
}

TEST(Polynomial, ExpansionHasKnownCoefficients) {
  const Polynomial p = compile_field("(x + 2*y)^2 - z/4 + 3").polynomial();
  EXPECT_EQ(p.to_string(), "x^2 + 4*x*y + 4*y^2 - 0.25*z + 3");
  Field kummer = compile_field(test::kKummer);
  kummer.set_parameter("mu", 1.5);
  const Polynomial k = kummer.polynomial();
  // Constant term F(0) = (3 - mu)·mu² - (3mu - 1).
  ASSERT_FALSE(k.terms().empty());
  EXPECT_EQ(k.terms().front().degree(), 0);
  EXPECT_NEAR(k.terms().front().c, 1.5 * 1.5 * 1.5 - 3.5, 1e-14);
  // x^4 only comes from (3 - mu)(x² + …)²: x enters p·q·r·s only as p·q = (1-z)² - 2x².
  int found = 0;
  for (const Monomial& m : k.terms()) {
    if (m.i != 4) continue;
    EXPECT_NEAR(m.c, 1.5, 1e-13);
    ++found;
  }
  EXPECT_EQ(found, 1);
}

TEST(Polynomial, RestrictionToLineAgreesWithField) {
  std::mt19937 rng(22);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (const auto& surface : test::polynomial_surfaces()) {
    SCOPED_TRACE(surface.source);
    const Field f = test::compile(surface);
    const Polynomial p = f.polynomial();
    Evaluator ev(f);
    std::vector<double> a(static_cast<std::size_t>(p.degree() + 1));
    for (int line = 0; line < 20; ++line) {
      const Vec3 o(u(rng), u(rng), u(rng));
      const Vec3 d = Vec3(u(rng), u(rng), u(rng)).normalized();
      p.restrict_to_line(o, d, a);
      EXPECT_EQ(a, p.restrict_to_line(o, d));
      for (int k = 0; k < 5; ++k) {
        const double t = u(rng);
        const Vec3 x = o + t * d;
        const double scale = std::max(
            1.0, term_scale(p, x) + term_scale(p, o.cwiseAbs() + std::abs(t) * d.cwiseAbs()));
        EXPECT_NEAR(horner(a, t), ev.value(x), 1e-12 * scale) << "t = " << t;
      }
    }
  }
}

TEST(Polynomial, RestrictionOfHighDegreeAgreesWithValue) {
  // Degree 40 is beyond the stack scratch of restrict_to_line.
  const Polynomial p({{40, 0, 0, 1.0}, {0, 20, 20, -2.0}, {1, 2, 3, 0.5}, {0, 0, 0, -1.0}});
  const Vec3 o(0.3, -0.2, 0.5), d(0.4, 0.6, -0.2);
  const std::vector<double> a = p.restrict_to_line(o, d);
  ASSERT_EQ(a.size(), 41U);
  for (const double t : {-1.0, -0.3, 0.0, 0.7, 1.2})
    EXPECT_NEAR(horner(a, t), p.value(o + t * d), 1e-12 * std::max(1.0, term_scale(p, o + t * d)));
}

TEST(Polynomial, RestrictionRejectsWrongOutputSize) {
  const Polynomial p({{2, 0, 0, 1.0}});
  std::vector<double> out(2);
  EXPECT_THROW(p.restrict_to_line(Vec3::Zero(), Vec3::UnitX(), out), InvalidArgument);
  EXPECT_TRUE(Polynomial().restrict_to_line(Vec3::Zero(), Vec3::UnitX()).empty());
}

TEST(Polynomial, ConstructorMergesSortsAndDropsZeros) {
  const Polynomial p({{0, 0, 2, 1.0},
                      {1, 0, 0, 2.0},
                      {0, 0, 0, -1.0},
                      {1, 0, 0, -2.0},
                      {2, 0, 0, 1.0},
                      {0, 2, 0, 0.5},
                      {0, 2, 0, 0.5}});
  ASSERT_EQ(p.terms().size(), 4U);
  // By degree, then (i, j, k): 1, then z^2 (0,0,2) < y^2 (0,2,0) < x^2 (2,0,0).
  EXPECT_EQ(p.terms()[0].degree(), 0);
  EXPECT_EQ(p.terms()[1].k, 2);
  EXPECT_EQ(p.terms()[2].j, 2);
  EXPECT_EQ(p.terms()[2].c, 1.0);
  EXPECT_EQ(p.terms()[3].i, 2);
  EXPECT_EQ(p.degree(), 2);
  EXPECT_TRUE(Polynomial({{1, 1, 1, 0.0}}).is_zero());
  EXPECT_EQ(Polynomial().degree(), -1);
  EXPECT_THROW(Polynomial({{-1, 0, 0, 1.0}}), InvalidArgument);
}

TEST(Polynomial, ValueGradientMatchesField) {
  for (const auto& surface : test::polynomial_surfaces()) {
    SCOPED_TRACE(surface.source);
    const Field f = test::compile(surface);
    const Polynomial p = f.polynomial();
    Evaluator ev(f);
    for (const Vec3& x : test::random_points(20, 1.5, 23)) {
      Vec3 gp, gf;
      const double vp = p.value_gradient(x, gp);
      const double vf = ev.value_gradient(x, gf);
      const double scale = std::max(1.0, 10 * term_scale(p, x));
      EXPECT_NEAR(vp, vf, 1e-13 * scale);
      EXPECT_LE((gp - gf).cwiseAbs().maxCoeff(), 1e-12 * scale) << x.transpose();
    }
  }
}

TEST(Polynomial, TranslatedMovesTheOrigin) {
  Field torus = compile_field(test::kTorus);
  torus.set_parameters({{"R", 1.0}, {"r", 0.3}});
  const Polynomial p = torus.polynomial();
  const Vec3 o(0.4, -1.1, 0.25);
  const Polynomial q = p.translated(o);
  EXPECT_EQ(q.degree(), p.degree());
  for (const Vec3& x : test::random_points(20, 1.0, 24))
    EXPECT_NEAR(q.value(x), p.value(x + o), 1e-12 * std::max(1.0, term_scale(p, x + o)));
}

TEST(Polynomial, NormalizedScalesLargestCoefficientToOne) {
  const Polynomial p({{2, 0, 0, -8.0}, {0, 0, 0, 2.0}});
  const Polynomial n = p.normalized();
  EXPECT_EQ(n.terms()[0].c, 0.25);
  EXPECT_EQ(n.terms()[1].c, -1.0);
  EXPECT_TRUE(Polynomial().normalized().is_zero());
}

TEST(Polynomial, ToStringWritesHighestDegreeFirstAndParsesBack) {
  EXPECT_EQ(Polynomial({{0, 0, 0, -1.0}, {2, 0, 0, 1.0}, {0, 2, 0, 1.0}}).to_string(),
            "x^2 + y^2 - 1");
  EXPECT_EQ(Polynomial({{1, 1, 1, -1.0}, {0, 0, 1, 2.5}}).to_string(), "-x*y*z + 2.5*z");
  EXPECT_EQ(Polynomial().to_string(), "0");
  Field barth = compile_field(test::kBarth);
  barth.set_parameter("phi", 1.6180339887498949);
  const Polynomial p = barth.polynomial();
  const Polynomial back = compile_field(p.to_string()).polynomial();
  ASSERT_EQ(back.terms().size(), p.terms().size());
  for (std::size_t i = 0; i < p.terms().size(); ++i) EXPECT_EQ(back.terms()[i].c, p.terms()[i].c);
}

TEST(Polynomial, FieldRefusesToExpandWhatIsNotAPolynomial) {
  EXPECT_THROW((void)compile_field("sin(x)").polynomial(), BadInput);
  EXPECT_THROW((void)compile_field("x/y").polynomial(), BadInput);
  EXPECT_THROW((void)compile_field("(x + y + z)^25").polynomial(), BadInput);  // too large
  EXPECT_THROW((void)compile_field("mu*x").polynomial(), InvalidArgument);     // no value
  EXPECT_EQ(compile_field("(x + y + z)^24").polynomial().terms().size(), 325U);
}

TEST(Polynomial, ConstantFieldExpandsToConstant) {
  Field f = compile_field("a^2 + sqrt(2)");
  f.set_parameter("a", 3);
  const Polynomial p = f.polynomial();
  ASSERT_EQ(p.terms().size(), 1U);
  EXPECT_EQ(p.terms()[0].c, 9 + std::sqrt(2.0));
  EXPECT_EQ(p.degree(), 0);
}

}  // namespace
}  // namespace zeroset
