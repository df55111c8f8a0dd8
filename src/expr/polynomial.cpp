#include "zeroset/expr/polynomial.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "tape_detail.h"
#include "zeroset/error.h"

namespace zeroset {
namespace {

bool term_less(const Monomial& a, const Monomial& b) {
  return std::make_tuple(a.degree(), a.i, a.j, a.k) < std::make_tuple(b.degree(), b.i, b.j, b.k);
}

bool same_exponents(const Monomial& a, const Monomial& b) {
  return a.i == b.i && a.j == b.j && a.k == b.k;
}

/// Index of the first coefficient of row a in a triangular table of rows 0..n of lengths
/// 1, 2, …, n+1.
constexpr std::size_t row(int a) { return static_cast<std::size_t>(a) * (a + 1) / 2; }

/// Degrees up to this restrict to a line with scratch on the stack, without allocating.
constexpr int kMaxStackDegree = 32;
/// Scratch: three tables of powers (o + t·d)^a plus the partial sums per power of x.
constexpr std::size_t scratch_size(int degree) { return 4 * row(degree + 1); }

void restrict_with(const std::vector<Monomial>& terms, int degree, const Vec3& o, const Vec3& d,
                   std::span<double> out, std::span<double> scratch) {
  const std::size_t table = row(degree + 1);
  std::span<double> powers[3] = {scratch.subspan(0, table), scratch.subspan(table, table),
                                 scratch.subspan(2 * table, table)};
  // Partial sums R_i(t) = Σ_{j,k} c_ijk (o_y + t d_y)^j (o_z + t d_z)^k, row i of length
  // degree - i + 1, stored back to back.
  std::span<double> partial = scratch.subspan(3 * table, table);
  std::fill(partial.begin(), partial.end(), 0.0);
  for (int axis = 0; axis < 3; ++axis) {
    std::span<double> p = powers[axis];
    p[0] = 1.0;
    for (int a = 1; a <= degree; ++a) {
      // (o + t d)^a = (o + t d)^(a-1) · (o + t d)
      const double* prev = &p[row(a - 1)];
      double* cur = &p[row(a)];
      cur[a] = 0.0;
      for (int m = 0; m < a; ++m) cur[m] = prev[m] * o[axis];
      for (int m = 0; m < a; ++m) cur[m + 1] += prev[m] * d[axis];
    }
  }
  auto partial_row = [&](int i) {  // Σ_{i' < i} (degree - i' + 1)
    return static_cast<std::size_t>(i) * static_cast<std::size_t>(degree + 1) - row(i - 1);
  };
  for (const Monomial& m : terms) {
    double* r = &partial[partial_row(m.i)];
    const double* py = &powers[1][row(m.j)];
    const double* pz = &powers[2][row(m.k)];
    for (int a = 0; a <= m.j; ++a) {
      const double ca = m.c * py[a];
      for (int b = 0; b <= m.k; ++b) r[a + b] += ca * pz[b];
    }
  }
  std::fill(out.begin(), out.end(), 0.0);
  for (int i = 0; i <= degree; ++i) {
    const double* r = &partial[partial_row(i)];
    const double* px = &powers[0][row(i)];
    for (int a = 0; a <= i; ++a)
      for (int b = 0; b <= degree - i; ++b) out[static_cast<std::size_t>(a + b)] += px[a] * r[b];
  }
}

}  // namespace

Polynomial::Polynomial(std::vector<Monomial> terms) {
  for (const Monomial& m : terms)
    if (m.i < 0 || m.j < 0 || m.k < 0)
      throw InvalidArgument(fmt::format(
          "polynomial term x^{} y^{} z^{}: exponents must not be negative", m.i, m.j, m.k));
  std::sort(terms.begin(), terms.end(), term_less);
  for (const Monomial& m : terms) {
    if (!terms_.empty() && same_exponents(terms_.back(), m))
      terms_.back().c += m.c;
    else
      terms_.push_back(m);
  }
  std::erase_if(terms_, [](const Monomial& m) { return m.c == 0.0; });
}

int Polynomial::degree() const { return terms_.empty() ? -1 : terms_.back().degree(); }

double Polynomial::value(const Vec3& p) const {
  double sum = 0;
  for (const Monomial& m : terms_)
    sum += m.c * detail::int_pow(p.x(), m.i) * detail::int_pow(p.y(), m.j) *
           detail::int_pow(p.z(), m.k);
  return sum;
}

double Polynomial::value_gradient(const Vec3& p, Vec3& gradient) const {
  double sum = 0;
  gradient.setZero();
  for (const Monomial& m : terms_) {
    const double px = detail::int_pow(p.x(), m.i);
    const double py = detail::int_pow(p.y(), m.j);
    const double pz = detail::int_pow(p.z(), m.k);
    sum += m.c * px * py * pz;
    if (m.i > 0) gradient.x() += m.c * m.i * detail::int_pow(p.x(), m.i - 1) * py * pz;
    if (m.j > 0) gradient.y() += m.c * m.j * px * detail::int_pow(p.y(), m.j - 1) * pz;
    if (m.k > 0) gradient.z() += m.c * m.k * px * py * detail::int_pow(p.z(), m.k - 1);
  }
  return sum;
}

void Polynomial::restrict_to_line(const Vec3& o, const Vec3& d, std::span<double> out) const {
  const int n = degree();
  if (out.size() != static_cast<std::size_t>(n + 1))
    throw InvalidArgument(fmt::format(
        "restrict_to_line: the output needs {} coefficients, it has {}", n + 1, out.size()));
  if (n < 0) return;
  if (n <= kMaxStackDegree) {
    std::array<double, scratch_size(kMaxStackDegree)> scratch;
    restrict_with(terms_, n, o, d, out, scratch);
  } else {
    std::vector<double> scratch(scratch_size(n));
    restrict_with(terms_, n, o, d, out, scratch);
  }
}

std::vector<double> Polynomial::restrict_to_line(const Vec3& o, const Vec3& d) const {
  std::vector<double> out(static_cast<std::size_t>(degree() + 1));
  restrict_to_line(o, d, out);
  return out;
}

Polynomial Polynomial::translated(const Vec3& o) const {
  // (x + o_x)^i = Σ_a C(i, a) o_x^(i-a) x^a, and likewise for y and z.
  auto expand = [](double shift, int n) {
    std::vector<double> c(static_cast<std::size_t>(n + 1));
    double binomial = 1.0;
    for (int a = 0; a <= n; ++a) {
      c[static_cast<std::size_t>(a)] = binomial * detail::int_pow(shift, n - a);
      binomial = binomial * (n - a) / (a + 1);
    }
    return c;
  };
  std::vector<Monomial> out;
  for (const Monomial& m : terms_) {
    const std::vector<double> cx = expand(o.x(), m.i);
    const std::vector<double> cy = expand(o.y(), m.j);
    const std::vector<double> cz = expand(o.z(), m.k);
    for (int a = 0; a <= m.i; ++a)
      for (int b = 0; b <= m.j; ++b)
        for (int c = 0; c <= m.k; ++c)
          out.push_back({a, b, c,
                         m.c * cx[static_cast<std::size_t>(a)] * cy[static_cast<std::size_t>(b)] *
                             cz[static_cast<std::size_t>(c)]});
  }
  return Polynomial(std::move(out));
}

Polynomial Polynomial::normalized() const {
  double largest = 0;
  for (const Monomial& m : terms_) largest = std::max(largest, std::abs(m.c));
  if (largest == 0 || !std::isfinite(largest)) return *this;
  Polynomial p = *this;
  for (Monomial& m : p.terms_) m.c /= largest;
  return p;
}

std::string Polynomial::to_string() const {
  if (terms_.empty()) return "0";
  std::string out;
  // Highest degree first, as one writes polynomials.
  for (auto it = terms_.rbegin(); it != terms_.rend(); ++it) {
    const Monomial& m = *it;
    std::string monomial;
    const std::pair<char, int> factors[3] = {{'x', m.i}, {'y', m.j}, {'z', m.k}};
    for (const auto& [name, power] : factors) {
      if (power == 0) continue;
      if (!monomial.empty()) monomial += '*';
      monomial += power == 1 ? fmt::format("{}", name) : fmt::format("{}^{}", name, power);
    }
    const double magnitude = std::abs(m.c);
    if (out.empty())
      out += m.c < 0 ? "-" : "";
    else
      out += m.c < 0 ? " - " : " + ";
    if (monomial.empty())
      out += fmt::format("{}", magnitude);
    else if (magnitude == 1.0)
      out += monomial;
    else
      out += fmt::format("{}*{}", magnitude, monomial);
  }
  return out;
}

}  // namespace zeroset
