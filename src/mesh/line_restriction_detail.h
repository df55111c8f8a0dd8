#pragma once
// F restricted to the grid lines of the polygonizer: the row sampler evaluates it at the
// nodes, the vertex placer refines the crossings on it, and both get the same bits for a node.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include "cell_triangulation_detail.h"
#include "polygonize_detail.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset::detail {

// A polynomial F restricted to the grid lines along one axis. Along the line through grid
// coordinates (u, v) of the other two axes (in increasing axis order), F is a univariate
// polynomial in t, the number of cells from the middle node of the whole line: G(t, u, v) =
// F with the axis coordinate coord(mid) + h·t, expanded once. Its coefficient of t^m is a
// polynomial in u whose coefficients depend on v alone; those are kept for the last v (set_v),
// since callers walk lines with v fixed (a layer of rows, the edges of one row), so a line then
// costs one Horner pass in u per coefficient. A node gets the bit-identical value whichever
// caller (a slab, a brick) evaluates it along this axis with the same u and v.
class LineRestriction {
 public:
  LineRestriction(const Polynomial& poly, const Grid& grid, int axis)
      : degree_(poly.degree()), mid_(grid.cells[static_cast<size_t>(axis)] / 2) {
    if (degree_ < 0) return;
    Vec3 origin = Vec3::Zero();
    origin[axis] = grid.coord(axis, mid_);
    const int ua = axis == 0 ? 1 : 0, va = axis == 2 ? 1 : 2;
    const Polynomial translated = poly.translated(origin);
    for (const Monomial& m : translated.terms()) {
      const int e[3] = {m.i, m.j, m.k};
      terms_.push_back({m.c * std::pow(grid.h, e[axis]), e[axis], e[ua], e[va]});
    }
    const size_t n = static_cast<size_t>(degree_ + 1);
    in_u_.resize(n * n);
    v_powers_.resize(n);
  }

  /// −1 for the zero polynomial.
  int degree() const { return degree_; }
  /// t of grid index `index` along the axis.
  double t_of(long long index) const { return static_cast<double>(index - mid_); }

  /// Prepares the lines through this v (kept until another v is set).
  void set_v(double v) {
    if (have_v_ && v == v_) return;
    const size_t n = static_cast<size_t>(degree_ + 1);
    v_powers_[0] = 1;
    for (size_t a = 1; a < n; ++a) v_powers_[a] = v_powers_[a - 1] * v;
    std::fill(in_u_.begin(), in_u_.end(), 0.0);
    for (const Term& m : terms_)
      in_u_[static_cast<size_t>(m.t) * n + static_cast<size_t>(m.u)] +=
          m.c * v_powers_[static_cast<size_t>(m.v)];
    v_ = v, have_v_ = true;
  }

  /// c[m · stride], m = 0..degree: F along the line through (u, v), v the last one set.
  void coefficients_at(double u, double* c, size_t stride) const {
    const size_t n = static_cast<size_t>(degree_ + 1);
    for (size_t m = 0; m < n; ++m) {
      const double* d = &in_u_[m * n];
      double sum = d[n - 1 - m];  // u's degree in the t^m coefficient is at most degree − m
      for (size_t a = n - 1 - m; a-- > 0;) sum = madd(sum, u, d[a]);
      c[m * stride] = sum;
    }
  }

#if defined(__AVX2__) && defined(__FMA__)
  /// The same for four lines through the last v at once, u's lanes: c[m · stride + lane].
  /// Each lane gets the bits of the scalar form.
  void coefficients_at(__m256d u, double* c, size_t stride) const {
    const size_t n = static_cast<size_t>(degree_ + 1);
    for (size_t m = 0; m < n; ++m) {
      const double* d = &in_u_[m * n];
      __m256d sum = _mm256_broadcast_sd(&d[n - 1 - m]);
      for (size_t a = n - 1 - m; a-- > 0;)
        sum = _mm256_fmadd_pd(sum, u, _mm256_broadcast_sd(&d[a]));
      _mm256_storeu_pd(c + m * stride, sum);
    }
  }
#endif

  /// c[0..degree] of F along the line through (u, v).
  void coefficients(double u, double v, double* c) {
    set_v(v);
    coefficients_at(u, c, 1);
  }

 private:
  struct Term {
    double c;
    int t, u, v;
  };
  int degree_;
  long long mid_;
  std::vector<Term> terms_;
  std::vector<double> in_u_;  // [m · (degree + 1) + a]: coefficient of t^m u^a at v_
  std::vector<double> v_powers_;
  double v_ = 0;
  bool have_v_ = false;
};

}  // namespace zeroset::detail
