#include "zeroset/expr/parse.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "surfaces.h"
#include "zeroset/error.h"

namespace zeroset {
namespace {

double eval(std::string_view source, const Vec3& p = Vec3::Zero()) {
  return Evaluator(compile_field(source)).value(p);
}

struct Malformed {
  std::string source;
  int line;
  int column;
  std::string message;  ///< expected substring of the first diagnostic's message
};

std::ostream& operator<<(std::ostream& os, const Malformed& m) {
  return os << '"' << m.source << '"';
}

class ParserRejects : public testing::TestWithParam<Malformed> {};

TEST_P(ParserRejects, WithMessageAtLineAndColumn) {
  const Malformed& m = GetParam();
  ParseResult r;
  ASSERT_NO_THROW(r = parse_field(m.source));
  ASSERT_FALSE(r.ok());
  EXPECT_FALSE(r.field.has_value());
  ASSERT_FALSE(r.diagnostics.empty());
  const Diagnostic& d = r.diagnostics.front();
  EXPECT_NE(d.message.find(m.message), std::string::npos) << "message: " << d.message;
  EXPECT_EQ(d.line, m.line) << d.message;
  EXPECT_EQ(d.column, m.column) << d.message;
}

const std::string kDeep = std::string(300, '(') + "x" + std::string(300, ')');

INSTANTIATE_TEST_SUITE_P(
    Table, ParserRejects,
    testing::Values(
        Malformed{"x^2 +", 1, 5, "expected an operand after '+'"},
        Malformed{"x^", 1, 2, "expected an operand after '^'"},
        Malformed{"x ** * 2", 1, 3, "expected an operand after '**', found '*'"},
        Malformed{"x +\n\n  * y", 1, 3, "expected an operand after '+'"},
        Malformed{"a = 1\nb = a +\n", 2, 7, "expected an operand after '+'"},
        Malformed{"(x + 1", 1, 7, "missing ')' to close '(' at column 1"},
        Malformed{"x * (y + (z - 1)", 1, 17, "missing ')' to close '(' at column 5"},
        Malformed{"sqrt(x", 1, 7, "missing ')' to close '(' at column 5"},
        Malformed{"(x + y\n  + z", 2, 6, "missing ')' to close '(' at line 1, column 1"},
        Malformed{"x^2 )", 1, 5, "unmatched ')'"}, Malformed{"x)", 1, 2, "unmatched ')'"},
        Malformed{"foo(x)", 1, 1, "unknown function 'foo'"},
        Malformed{"x + mu(x+1)", 1, 5, "unknown function 'mu'"},
        Malformed{"sqrt(x, y)", 1, 1, "'sqrt' takes 1 argument, but 2 were given"},
        Malformed{"1 + sin()", 1, 5, "'sin' takes 1 argument, but 0 were given"},
        Malformed{"sin x", 1, 1, "expected '(' after the function 'sin'"},
        Malformed{"x + $", 1, 5, "unexpected character '$'"},
        Malformed{"a = 1;\n\t$", 2, 2, "unexpected character '$'"},
        Malformed{"x × y", 1, 3, "unexpected character '×'"},
        Malformed{"ü + x", 1, 1, "unexpected character 'ü'"},
        Malformed{"x\x01", 1, 2, "unexpected byte 0x01"}, Malformed{"", 1, 1, "empty input"},
        Malformed{"  # only a comment\n", 1, 1, "empty input"},
        Malformed{"x = 1; x^2", 1, 1, "cannot define 'x'"},
        Malformed{"pi = 3; pi*x", 1, 1, "cannot redefine the constant 'pi'"},
        Malformed{"sin = 2; sin(x)", 1, 1, "cannot define 'sin': it is a function"},
        Malformed{"p = 1; p = 2; p*x", 1, 8, "'p' is already defined on line 1"},
        Malformed{"a = b + 1; b = 2; a*x", 1, 5, "'b' is used before its definition on line 1"},
        Malformed{"a = a + x; a", 1, 5, "'a' is used in its own definition"},
        Malformed{"1..2 + x", 1, 1, "malformed number '1..2'"},
        Malformed{"x + 1.2.3", 1, 5, "malformed number '1.2.3'"},
        Malformed{". + x", 1, 1, "malformed number '.'"},
        Malformed{"1e999*x", 1, 1, "out of the range"},
        Malformed{"x = y = z", 1, 7, "an equation has only one '='"},
        Malformed{"p = 1 = 2; p", 1, 7, "a definition has only one '='"},
        Malformed{"p = 1 - z;", 1, 1, "the definition of 'p' is not followed by"},
        Malformed{"x^2 + y^2\nz^2", 1, 1, "expected a definition 'name = expression'"},
        Malformed{"2x + 1", 1, 2, "expected an operator"},
        Malformed{"2e + 1", 1, 2, "expected an operator"},  // 2 followed by the constant e
        Malformed{"x y", 1, 3, "expected an operator"},
        Malformed{"(x)(y)", 1, 4, "expected an operator"},
        Malformed{"(2x)", 1, 3, "expected an operator"},
        Malformed{"pi(2)", 1, 3, "expected an operator"}, Malformed{"x, y", 1, 2, "unexpected ','"},
        Malformed{"x + ()", 1, 5, "expected an expression inside '()'"},
        Malformed{"x = ", 1, 3, "expected an expression after '='"},
        Malformed{"x^2 + y^2 - 1 = ", 1, 15, "expected an expression after '='"},
        Malformed{"* x", 1, 1, "expected an expression, found '*'"},
        Malformed{kDeep, 1, 257, "nested too deeply"},
        Malformed{std::string(300, '-') + "x", 1, 257, "nested too deeply"}));

TEST(Parser, SuggestsMultiplicationForImplicitProduct) {
  const ParseResult r = parse_field("2x + 1");
  ASSERT_EQ(r.diagnostics.size(), 1U);
  EXPECT_EQ(r.diagnostics[0].hint, "did you mean 2*x?");
}

TEST(Parser, ReportsColumnOfUnknownName) {
  const ParseResult r = parse_field("x^2 + bar(y)");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.diagnostics[0].column, 7);
  EXPECT_EQ(r.diagnostics[0].length, 3);
}

TEST(Parser, FormatsDiagnosticWithSourceLineAndCaret) {
  const ParseResult r = parse_field("x^2 +");
  ASSERT_EQ(r.diagnostics.size(), 1U);
  EXPECT_EQ(r.format(), "line 1, column 5: expected an operand after '+'\n  x^2 +\n      ^");
  const Diagnostic d{2, 3, 3, "unknown function 'foo'", "try this"};
  EXPECT_EQ(d.format("a = 1\n\tfoo(x)"),
            "line 2, column 3: unknown function 'foo'\n  \tfoo(x)\n  \t ^~~\n  hint: try this");
}

TEST(Parser, ReportsProblemsOnSeveralLines) {
  // Line 2 continues on line 3 after its '+' (and inside the parentheses to line 4), where a
  // second '=' is the problem.
  const ParseResult r = parse_field("a = $\nb = 1 +\nc = (x\n)\nd = foo(x)\na*b*c*d");
  ASSERT_EQ(r.diagnostics.size(), 3U) << r.format();
  EXPECT_EQ(r.diagnostics[0].line, 1);
  EXPECT_EQ(r.diagnostics[1].line, 3);
  EXPECT_EQ(r.diagnostics[2].line, 5);
}

TEST(Parser, CompileFieldThrowsParseErrorWithPosition) {
  try {
    compile_field("x^2 + foo(y)");
    FAIL() << "no exception";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_EQ(e.column(), 7);
    EXPECT_EQ(e.message(), "unknown function 'foo'");
    EXPECT_NE(std::string(e.what()).find("  x^2 + foo(y)\n        ^~~"), std::string::npos)
        << e.what();
  }
}

TEST(Parser, ReadsNumbersInEveryNotation) {
  EXPECT_EQ(eval("1.5"), 1.5);
  EXPECT_EQ(eval("2e-3"), 2e-3);
  EXPECT_EQ(eval(".5"), 0.5);
  EXPECT_EQ(eval("3."), 3.0);
  EXPECT_EQ(eval("1E+2"), 100.0);
}

TEST(Parser, AppliesPrecedenceAndAssociativity) {
  EXPECT_EQ(eval("2^3^2"), 512.0);
  EXPECT_EQ(eval("2**3**2"), 512.0);
  EXPECT_EQ(eval("-2^2"), -4.0);
  EXPECT_EQ(eval("(-2)^2"), 4.0);
  EXPECT_EQ(eval("2^-1"), 0.5);
  EXPECT_EQ(eval("-x^2", {3, 0, 0}), -9.0);
  EXPECT_EQ(eval("8/2/2"), 2.0);
  EXPECT_EQ(eval("2-3-4"), -5.0);
  EXPECT_EQ(eval("1 + 2*3^2"), 19.0);
  EXPECT_EQ(eval("--3 + +2"), 5.0);
  EXPECT_EQ(eval("2*-3"), -6.0);
  EXPECT_EQ(eval("pi"), std::numbers::pi);
  EXPECT_EQ(eval("e"), std::numbers::e);
}

TEST(Parser, ReadsEquationAsDifference) {
  const Vec3 p(0.3, -0.7, 1.1);
  EXPECT_EQ(eval("x^2 + y^2 = z^2", p), eval("x^2 + y^2 - (z^2)", p));
  EXPECT_EQ(eval("z = x*y", p), p.z() - p.x() * p.y());
}

TEST(Parser, AcceptsDefinitionsNewlinesAndComments) {
  const std::string multiline =
      "# Kummer's quartic\n"
      "p = 1-z-sqrt(2)*x   # first plane\n"
      "q = 1-z+sqrt(2)*x\r\n"
      "r = 1+z+sqrt(2)*y; s = 1+z-sqrt(2)*y\n"
      "\n"
      "(3-mu)*(x^2+y^2+z^2-mu)^2 -\n"
      "  (3*mu-1)*p*q\n"
      "            *r*s\n";
  Field a = compile_field(multiline);
  Field b = compile_field(test::kKummer);
  a.set_parameter("mu", 1.3);
  b.set_parameter("mu", 1.3);
  Evaluator ea(a), eb(b);
  for (const Vec3& p : test::random_points(10, 1.5, 3)) EXPECT_EQ(ea.value(p), eb.value(p));
  EXPECT_EQ(a.parameter_names(), std::vector<std::string>{"mu"});
}

TEST(Parser, AcceptsTrailingSeparators) {
  EXPECT_EQ(eval("x + 1;", {1, 0, 0}), 2.0);
  EXPECT_EQ(eval("a = 2;; a*x\n\n", {1, 0, 0}), 2.0);
  EXPECT_EQ(eval("z = x^2;", {2, 0, 5}), 1.0);  // a coordinate is never a definition
}

TEST(Parser, NeverThrowsOnRandomInput) {
  const std::string alphabet = "xyz0123456789.e+-*/^()=;,\n #$sqrtpiabmu";
  std::mt19937 rng(1);
  std::uniform_int_distribution<std::size_t> pick(0, alphabet.size() - 1);
  std::uniform_int_distribution<int> length(0, 40);
  int ok = 0;
  for (int i = 0; i < 5000; ++i) {
    std::string s;
    for (int n = length(rng); n > 0; --n) s += alphabet[pick(rng)];
    ParseResult r;
    ASSERT_NO_THROW(r = parse_field(s)) << s;
    ASSERT_EQ(r.ok(), r.diagnostics.empty()) << s;
    if (!r.ok()) {
      ASSERT_NO_THROW((void)r.format()) << s;
      continue;
    }
    ++ok;
    for (const std::string& name : r.field->parameter_names()) r.field->set_parameter(name, 1.3);
    Evaluator ev(*r.field);
    ASSERT_NO_THROW((void)ev.sample({0.1, 0.2, 0.3})) << s;
  }
  EXPECT_GT(ok, 100);
}

TEST(Parser, HandlesHugeInput) {
  std::string source = "x";
  for (int i = 0; i < 100000; ++i) source += " + x";
  EXPECT_EQ(eval(source, {1, 0, 0}), 100001.0);
  std::string defs;
  for (int i = 0; i < 5000; ++i)
    defs += i == 0 ? fmt::format("a0 = x + 1\n") : fmt::format("a{} = a{} + 1\n", i, i - 1);
  defs += "a4999";
  EXPECT_EQ(eval(defs, {1, 0, 0}), 5001.0);
  const ParseResult deep = parse_field(std::string(100000, '(') + "x");
  ASSERT_FALSE(deep.ok());
  EXPECT_NE(deep.diagnostics[0].message.find("nested too deeply"), std::string::npos);
}

TEST(Parser, AcceptsNestingUpToTheLimit) {
  const std::string source = std::string(200, '(') + "x" + std::string(200, ')');
  EXPECT_EQ(eval(source, {2, 0, 0}), 2.0);
}

}  // namespace
}  // namespace zeroset
