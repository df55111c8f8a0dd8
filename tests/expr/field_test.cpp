#include "zeroset/expr/field.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "surfaces.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset {
namespace {

using test::compile;
using test::random_points;

/// Fourth-order central difference of g at 0 with step h: error O(h^4), so h = 1e-3 leaves
/// truncation and rounding both far below the 1e-6 tolerance.
template <class G>
double central_difference(G g, double h = 1e-3) {
  return (8.0 * (g(h) - g(-h)) - (g(2 * h) - g(-2 * h))) / (12.0 * h);
}

double value_at(const Field& f, const Vec3& p) { return Evaluator(f).value(p); }

double max_abs(const Vec3& v) { return v.cwiseAbs().maxCoeff(); }

std::vector<test::Surface> all_surfaces() {
  std::vector<test::Surface> all = test::polynomial_surfaces();
  for (const auto& s : test::transcendental_surfaces()) all.push_back(s);
  return all;
}

bool same_value(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

TEST(Field, GradientMatchesFiniteDifferences) {
  for (const auto& surface : all_surfaces()) {
    SCOPED_TRACE(surface.source);
    Evaluator ev(compile(surface));
    for (const Vec3& p : random_points(40, 1.5, 11)) {
      Vec3 g;
      const double f = ev.value_gradient(p, g);
      const double scale = std::max({1.0, std::abs(f), max_abs(g)});
      for (int axis = 0; axis < 3; ++axis) {
        const double fd =
            central_difference([&](double h) { return ev.value(p + h * Vec3::Unit(axis)); });
        EXPECT_LE(std::abs(fd - g[axis]), 1e-6 * scale)
            << "axis " << axis << " at " << p.transpose();
      }
    }
  }
}

TEST(Field, HessianMatchesFiniteDifferencesOfGradient) {
  for (const auto& surface : all_surfaces()) {
    SCOPED_TRACE(surface.source);
    Evaluator ev(compile(surface));
    for (const Vec3& p : random_points(25, 1.5, 12)) {
      const FieldSample s = ev.sample(p);
      const double scale = std::max({1.0, max_abs(s.gradient), s.hessian.cwiseAbs().maxCoeff()});
      EXPECT_EQ(s.hessian, s.hessian.transpose());
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          const double fd = central_difference([&](double h) {
            Vec3 g;
            ev.value_gradient(p + h * Vec3::Unit(j), g);
            return g[i];
          });
          EXPECT_LE(std::abs(fd - s.hessian(i, j)), 1e-6 * scale)
              << "H(" << i << "," << j << ") at " << p.transpose();
        }
      }
    }
  }
}

TEST(Field, ParameterDerivativesMatchFiniteDifferences) {
  int checked = 0;
  for (const auto& surface : all_surfaces()) {
    SCOPED_TRACE(surface.source);
    const Field field = compile(surface);
    Evaluator ev(field);
    Evaluator shifted(field);
    for (const Vec3& p : random_points(20, 1.5, 13)) {
      const FieldSample s = ev.sample(p, Derivatives::kParameters);
      ASSERT_EQ(s.dq.size(), field.parameter_names().size());
      for (std::size_t k = 0; k < s.dq.size(); ++k) {
        const double q = field.parameter_values()[k];
        const double fd = central_difference([&](double h) {
          shifted.set_parameter(static_cast<int>(k), q + h);
          return shifted.value(p);
        });
        shifted.set_parameter(static_cast<int>(k), q);
        // x^n for a negative x has no derivative in n: both sides are NaN there.
        if (!std::isfinite(fd)) {
          EXPECT_FALSE(std::isfinite(s.dq[k]));
          continue;
        }
        EXPECT_LE(std::abs(fd - s.dq[k]),
                  1e-6 * std::max({1.0, std::abs(s.value), std::abs(s.dq[k])}))
            << field.parameter_names()[k] << " at " << p.transpose();
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 150);
}

TEST(Field, SampleAgreesWithValueAndGradient) {
  for (const auto& surface : all_surfaces()) {
    SCOPED_TRACE(surface.source);
    Evaluator ev(compile(surface));
    for (const Vec3& p : random_points(10, 1.5, 14)) {
      Vec3 g;
      const double f = ev.value_gradient(p, g);
      EXPECT_TRUE(same_value(f, ev.value(p)));
      for (const bool hessian : {false, true}) {
        const FieldSample s = ev.sample(p, hessian ? Derivatives::kAll : Derivatives::kParameters);
        EXPECT_TRUE(same_value(s.value, f));
        for (int k = 0; k < 3; ++k) EXPECT_TRUE(same_value(s.gradient[k], g[k]));
      }
    }
  }
}

TEST(Field, KummerHasNodeWhereTheoryPutsIt) {
  Field f = compile_field(test::kKummer);
  f.set_parameter("mu", 1.5);
  Evaluator ev(f);
  const FieldSample s = ev.sample({1.0606601718, -0.3535533906, -0.5});
  EXPECT_LT(std::abs(s.value), 1e-8);
  EXPECT_LT(s.gradient.norm(), 1e-8);
  EXPECT_GT(s.hessian.norm(), 1.0);  // a node, not a degenerate point
}

TEST(Field, IntegerPowersAreExactRepeatedMultiplication) {
  EXPECT_EQ(value_at(compile_field("(-2)^3"), Vec3::Zero()), -8.0);
  const Field x4 = compile_field("x^4");
  EXPECT_EQ(value_at(x4, {-1.5, 0, 0}), 5.0625);
  const double x = -1.1;
  EXPECT_EQ(value_at(x4, {x, 0, 0}), (x * x) * (x * x));
  EXPECT_EQ(value_at(compile_field("x^5"), {-2, 0, 0}), -32.0);
  EXPECT_EQ(value_at(compile_field("x**3"), {-3, 0, 0}), -27.0);
  EXPECT_EQ(value_at(compile_field("x^0"), {0, 0, 0}), 1.0);
  EXPECT_EQ(value_at(compile_field("x^-2"), {-2, 0, 0}), 0.25);
  EXPECT_EQ(value_at(compile_field("x^2.5"), {4, 0, 0}), 32.0);
}

TEST(Field, NonIntegerPowerOfNegativeBaseIsNaN) {
  EXPECT_TRUE(std::isnan(value_at(compile_field("x^2.5"), {-1, 0, 0})));
  EXPECT_TRUE(std::isnan(value_at(compile_field("(-8)^(1/3)"), Vec3::Zero())));
}

TEST(Field, VariableExponentIsExpOfProductWithLog) {
  const Field f = compile_field("x^y");
  EXPECT_NEAR(value_at(f, {2, 3, 0}), 8.0, 1e-14);
  EXPECT_DOUBLE_EQ(value_at(f, {1.7, 0.3, 0}), std::exp(0.3 * std::log(1.7)));
  EXPECT_TRUE(std::isnan(value_at(f, {-2, 3, 0})));  // pow semantics via exp(y·log x)
}

TEST(Field, ParameterExponentIsExactWhenItIsAnInteger) {
  Field f = compile_field("x^n");
  f.set_parameter("n", 3);
  Evaluator ev(f);
  EXPECT_EQ(ev.value({-2, 0, 0}), -8.0);
  ev.set_parameter(0, -2);
  EXPECT_EQ(ev.value({-2, 0, 0}), 0.25);
  ev.set_parameter(0, 2.5);
  EXPECT_TRUE(std::isnan(ev.value({-2, 0, 0})));
  EXPECT_EQ(ev.value({4, 0, 0}), 32.0);
  std::vector<double> xs = {-2, 4}, zeros = {0, 0}, out(2);
  ev.values(xs, zeros, zeros, out);
  EXPECT_TRUE(std::isnan(out[0]));
  EXPECT_EQ(out[1], 32.0);
}

TEST(Field, BatchedEvaluationEqualsScalarEvaluation) {
  for (const auto& surface : all_surfaces()) {
    SCOPED_TRACE(surface.source);
    Evaluator ev(compile(surface));
    // 1000 is not a multiple of the block size, so the partial last block is covered.
    const std::vector<Vec3> points = random_points(1000, 1.5, 15);
    std::vector<double> x, y, z;
    for (const Vec3& p : points) {
      x.push_back(p.x());
      y.push_back(p.y());
      z.push_back(p.z());
    }
    const std::size_t n = points.size();
    std::vector<double> v(n), w(n), gx(n), gy(n), gz(n);
    ev.values(x, y, z, v);
    ev.values_gradients(x, y, z, w, gx, gy, gz);
    for (std::size_t i = 0; i < n; ++i) {
      Vec3 g;
      const double f = ev.value_gradient(points[i], g);
      ASSERT_TRUE(same_value(v[i], f)) << i;
      ASSERT_TRUE(same_value(w[i], f)) << i;
      ASSERT_TRUE(same_value(gx[i], g.x()) && same_value(gy[i], g.y()) && same_value(gz[i], g.z()))
          << i;
    }
  }
}

TEST(Field, BatchedHessiansEqualSampledHessians) {
  for (const auto& surface : all_surfaces()) {
    SCOPED_TRACE(surface.source);
    Evaluator ev(compile(surface));
    const std::vector<Vec3> points = random_points(300, 1.5, 16);  // a partial last block
    const std::size_t n = points.size();
    std::vector<double> x, y, z, v(n), gx(n), gy(n), gz(n);
    for (const Vec3& p : points) {
      x.push_back(p.x());
      y.push_back(p.y());
      z.push_back(p.z());
    }
    std::array<std::vector<double>, 6> h;
    for (auto& entry : h) entry.resize(n);
    ev.values_gradients_hessians(x, y, z, v, gx, gy, gz, {h[0], h[1], h[2], h[3], h[4], h[5]});
    for (std::size_t i = 0; i < n; ++i) {
      const FieldSample s = ev.sample(points[i], Derivatives::kHessian);
      ASSERT_TRUE(same_value(v[i], s.value)) << i;
      ASSERT_TRUE(same_value(gx[i], s.gradient.x()) && same_value(gy[i], s.gradient.y()) &&
                  same_value(gz[i], s.gradient.z()))
          << i;
      const double want[6] = {s.hessian(0, 0), s.hessian(0, 1), s.hessian(0, 2),
                              s.hessian(1, 1), s.hessian(1, 2), s.hessian(2, 2)};
      for (std::size_t k = 0; k < 6; ++k)
        ASSERT_TRUE(same_value(h[k][i], want[k])) << i << ' ' << k;
    }
  }
}

TEST(Field, BatchedEvaluationRejectsMismatchedSpans) {
  Evaluator ev(compile_field("x"));
  std::vector<double> a(3), b(2);
  EXPECT_THROW(ev.values(a, a, b, a), InvalidArgument);
  EXPECT_THROW(ev.values_gradients(a, a, a, a, a, b, a), InvalidArgument);
  EXPECT_THROW(ev.values_gradients_hessians(a, a, a, a, a, a, a, {a, a, a, a, b, a}),
               InvalidArgument);
  std::vector<double> empty;
  EXPECT_NO_THROW(ev.values(empty, empty, empty, empty));
}

TEST(Field, ConstantAndCoordinateOutputsFillWholeBatches) {
  // The value or a derivative can be a uniform (x + 3 has gradient (1, 0, 0)) or an input
  // slot (F = y): both must reach every point of the batch.
  for (const char* source : {"x + 3", "y", "7"}) {
    SCOPED_TRACE(source);
    Evaluator ev(compile_field(source));
    std::vector<double> x(70, 0.5), y(70, -2.0), z(70, 1.0), v(70), gx(70), gy(70), gz(70);
    ev.values_gradients(x, y, z, v, gx, gy, gz);
    Vec3 g;
    const double f = ev.value_gradient({0.5, -2.0, 1.0}, g);
    for (int i = 0; i < 70; ++i) {
      EXPECT_EQ(v[static_cast<std::size_t>(i)], f);
      EXPECT_EQ(gx[static_cast<std::size_t>(i)], g.x());
      EXPECT_EQ(gy[static_cast<std::size_t>(i)], g.y());
    }
  }
}

TEST(Field, EvaluationPropagatesNaNInsteadOfThrowing) {
  Evaluator ev(compile_field("sqrt(x) + log(y) + 1/z"));
  EXPECT_TRUE(std::isnan(ev.value({-1, 1, 1})));
  EXPECT_TRUE(std::isnan(ev.value({1, -1, 1})));
  EXPECT_TRUE(std::isinf(ev.value({1, 1, 0})));
  const FieldSample s = ev.sample({-1, 1, 1});
  EXPECT_TRUE(std::isnan(s.value));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> x = {nan, 1}, y = {1, 1}, z = {1, 1}, out(2);
  ev.values(x, y, z, out);
  EXPECT_TRUE(std::isnan(out[0]));
  EXPECT_EQ(out[1], 2.0);
}

TEST(Field, MissingParametersAreAllNamed) {
  const Field f = compile_field("a*x^2 + mu*y^2 - a*mu");
  EXPECT_EQ(f.missing_parameters(), (std::vector<std::string>{"a", "mu"}));
  try {
    Evaluator ev(f);
    FAIL() << "Evaluator accepted a field without parameter values";
  } catch (const InvalidArgument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("missing value for parameters a, mu"), std::string::npos) << what;
    EXPECT_NE(what.find("--param a=..."), std::string::npos) << what;
  }
  EXPECT_THROW(f.require_parameters(), InvalidArgument);
  Field g = f;
  g.set_parameter("a", 2);
  try {
    g.require_parameters();
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("missing value for parameter mu"), std::string::npos);
  }
  g.set_parameter("mu", 1);
  EXPECT_NO_THROW(g.require_parameters());
  EXPECT_NO_THROW(Evaluator{g});
}

TEST(Field, RejectsUnknownAndNonFiniteParameterValues) {
  Field f = compile_field("mu*x");
  EXPECT_THROW(f.set_parameter("nu", 1), InvalidArgument);
  EXPECT_THROW(f.set_parameter("mu", std::numeric_limits<double>::infinity()), InvalidArgument);
  EXPECT_THROW(f.set_parameter(1, 1.0), InvalidArgument);
  EXPECT_THROW(f.set_parameters({{"mu", 1}, {"other", 2}}), InvalidArgument);
  try {
    f.set_parameter("nu", 1);
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("nu"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("mu"), std::string::npos);
  }
}

TEST(Field, ParametersComeInOrderOfFirstAppearance) {
  const Field f = compile_field("b = beta*x; gamma*b + alpha*y + beta");
  EXPECT_EQ(f.parameter_names(), (std::vector<std::string>{"beta", "gamma", "alpha"}));
  EXPECT_EQ(f.parameter_index("alpha"), 2);
  EXPECT_EQ(f.parameter_index("b"), -1);
}

TEST(Field, ChangingParametersNeedsNoRecompilation) {
  Field f = compile_field(test::kKummer);
  f.set_parameter("mu", 1.5);
  Field g = f;
  g.set_parameter("mu", 2.0);
  EXPECT_EQ(&f.tape(), &g.tape());
  Evaluator ev(f);
  const Vec3 p(0.3, 0.2, 0.1);
  const double at_15 = ev.value(p);
  ev.set_parameter(0, 2.0);
  EXPECT_EQ(ev.value(p), value_at(g, p));
  EXPECT_NE(ev.value(p), at_15);
  ev.reset(f);
  EXPECT_EQ(ev.value(p), at_15);
}

TEST(Field, DegreeIsDecidedSymbolically) {
  struct Case {
    const char* source;
    int degree;
  };
  const Case cases[] = {{test::kKummer, 4},
                        {test::kBarth, 6},
                        {"x^2 + y^2 - z^2", 2},
                        {"x*y*z", 3},
                        {test::kDegree12, 12},
                        {"sin(x)", -1},
                        {"x^2.5", -1},
                        {"x/2", 1},
                        {"x/y", -1},
                        {"x/(mu + sqrt(2))", 1},
                        {"sqrt(2)*x^2 + sin(mu)*y", 2},
                        {"x^mu", -1},
                        {"x^-1", -1},
                        {"exp(x)", -1},
                        {"2^x", -1},
                        {"mu", 0},
                        {"3", 0},
                        {"x^2 = y", 2},
                        {"p = x^3; p^2 - 1", 6}};
  for (const Case& c : cases) {
    SCOPED_TRACE(c.source);
    const Field f = compile_field(c.source);
    EXPECT_EQ(f.degree(), c.degree);
    EXPECT_EQ(f.is_polynomial(), c.degree >= 0);
    EXPECT_EQ(f.is_expandable(), c.degree >= 0);
  }
}

TEST(Field, PolynomialsAboveTheExpansionLimitAreNotExpanded) {
  const Field f24 = compile_field("(x^2 + y^2 + z^2)^12 - 1");
  EXPECT_TRUE(f24.is_expandable());
  EXPECT_EQ(f24.polynomial().degree(), 24);
  const Field f26 = compile_field("(x^2 + y^2 + z^2)^13 - 1");
  EXPECT_TRUE(f26.is_polynomial());
  EXPECT_FALSE(f26.is_expandable());
  EXPECT_THROW((void)f26.polynomial(), BadInput);
  EXPECT_NEAR(value_at(f26, {1, 0, 0}), 0.0, 1e-15);  // still evaluated
}

TEST(Field, DefaultFieldIsZeroWithoutParameters) {
  const Field f;
  EXPECT_TRUE(f.parameter_names().empty());
  EXPECT_EQ(value_at(f, {1, 2, 3}), 0.0);
  EXPECT_EQ(f.degree(), 0);
}

TEST(Field, ExpressionStringSubstitutesDefinitions) {
  EXPECT_EQ(compile_field(test::kKummer).expression_string(),
            "(3 - mu)*(x^2 + y^2 + z^2 - mu)^2 - (3*mu - 1)*(1 - z - sqrt(2)*x)*"
            "(1 - z + sqrt(2)*x)*(1 + z + sqrt(2)*y)*(1 + z - sqrt(2)*y)");
  EXPECT_EQ(compile_field("x^2 + y^2 = z^2 + 1").expression_string(), "x^2 + y^2 - (z^2 + 1)");
  EXPECT_EQ(compile_field("a = x - y\n-a^2 + (-a)^3 + 2^-a").expression_string(),
            "-(x - y)^2 + (-(x - y))^3 + 2^-(x - y)");
}

TEST(Field, ExpressionStringEvaluatesLikeTheSource) {
  for (const auto& surface : all_surfaces()) {
    SCOPED_TRACE(surface.source);
    const Field f = compile(surface);
    test::Surface printed{f.expression_string(), surface.params};
    Evaluator a(f);
    Evaluator b(compile(printed));
    for (const Vec3& p : random_points(5, 1.5, 16)) EXPECT_TRUE(same_value(a.value(p), b.value(p)));
  }
}

TEST(Field, ExpressionStringFallsBackToSourceWhenSubstitutionExplodes) {
  std::string source = "a0 = x + y";
  for (int i = 1; i <= 30; ++i) source += fmt::format("; a{} = a{}*a{}", i, i - 1, i - 1);
  source += "; a30";
  const Field f = compile_field(source);
  EXPECT_EQ(f.expression_string(), source);
  EXPECT_EQ(value_at(f, {0.5, 0.5, 0}), 1.0);
}

}  // namespace
}  // namespace zeroset
