#pragma once
// Reference surfaces and helpers shared by the expr tests.
#include <map>
#include <random>
#include <string>
#include <vector>

#include "zeroset/expr/parse.h"
#include "zeroset/types.h"

namespace zeroset::test {

inline constexpr const char* kKummer =
    "p = 1-z-sqrt(2)*x; q = 1-z+sqrt(2)*x; r = 1+z+sqrt(2)*y; s = 1+z-sqrt(2)*y; "
    "(3-mu)*(x^2+y^2+z^2-mu)^2 - (3*mu-1)*p*q*r*s";
inline constexpr const char* kBarth =
    "4*(phi^2*x^2-y^2)*(phi^2*y^2-z^2)*(phi^2*z^2-x^2) - (1+2*phi)*(x^2+y^2+z^2-1)^2";
inline constexpr const char* kTorus = "(x^2+y^2+z^2+R^2-r^2)^2 - 4*R^2*(x^2+y^2)";
inline constexpr const char* kRoman = "x^2*y^2+y^2*z^2+z^2*x^2-x*y*z";
inline constexpr const char* kDegree12 = "((x^2+y^2+z^2-1)^2 - x*y*z)^3";

struct Surface {
  std::string source;
  std::map<std::string, double> params;
};

/// Polynomial surfaces with their parameter values.
inline std::vector<Surface> polynomial_surfaces() {
  return {{kKummer, {{"mu", 1.5}}},
          {kBarth, {{"phi", 1.6180339887498949}}},
          {kTorus, {{"R", 1.0}, {"r", 0.4}}},
          {kRoman, {}},
          {"x^2 + y^2 - z^2", {}},
          {"x*y*z", {}},
          {kDegree12, {}},
          {"a*x^3 - (y - b)^2/c + x*z/2 + 1", {{"a", 0.7}, {"b", -0.3}, {"c", 1.9}}}};
}

/// Surfaces that are not polynomials, each defined on the whole box [-1.5, 1.5]^3.
inline std::vector<Surface> transcendental_surfaces() {
  return {{"sin(x*y) + cos(z)^2 - 0.5", {}},
          {"exp(-x^2 - y^2) - z/3", {}},
          {"sqrt(x^2 + y^2 + 1) - z^2", {}},
          {"log(x^2 + y^2 + z^2 + 0.5)", {}},
          {"abs(x + 2*y + 7) - exp(z)*x", {}},
          {"tan(0.5*x*y) + z", {}},
          {"(x^2 + 1)^(y/2 + z) - 2^x", {}},
          {"(x^2 + 0.5)^k - y/(z^2 + 1) + a*sin(a*x)", {{"k", 2.5}, {"a", 0.8}}},
          {"x^n*y - z", {{"n", 3.0}}},
          {"1/(x^2 + y^2 + 1) - (z^2 + 1)^-2 + (x*y)^2/(1 + z^2)", {}},
          {"abs(x + 2*y + 0.5) - abs(z)^3", {}}};
}

/// Compiles a surface and sets its parameters; fails the test on a parse error.
inline Field compile(const Surface& s) {
  Field f = compile_field(s.source);
  f.set_parameters(s.params);
  return f;
}

/// Fixed-seed uniform points in the cube [-half, half]^3.
inline std::vector<Vec3> random_points(int count, double half, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-half, half);
  std::vector<Vec3> points;
  for (int i = 0; i < count; ++i) points.emplace_back(u(rng), u(rng), u(rng));
  return points;
}

}  // namespace zeroset::test
