#include "zeroset/render/raycast.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include "bernstein_detail.h"
#include "interval_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset {
namespace {

constexpr int kN = RootFinder::kMaxDegree + 1;
// |∇F| below this fraction of the magnitude of its terms counts as ∇F = 0 (see intersect).
constexpr double kRelativeGradientFloor = 1e-6;
// ∇F from the row's expansions is used when it exceeds that floor by this factor and the
// bound on its own rounding error by kRowGradientAccuracy (see intersect). That bound is a
// worst case, orders of magnitude above the actual error: the reference scenes shade the
// same as with ∇F from F's own terms.
constexpr double kRowGradientMargin = 1e3;
constexpr double kRowGradientAccuracy = 1e3;

constexpr double square(double x) { return x * x; }
/// |v|², with fused multiply-adds in the order the packets use.
inline double squared_norm(double x, double y, double z) {
  return std::fma(z, z, std::fma(y, y, x * x));
}
/// lo < x < ∞ (false for NaN).
inline bool in_open_range(double x, double lo) {
  return x > lo && x < std::numeric_limits<double>::infinity();
}

/// Number of monomials in x, y, z of degree ≤ D.
constexpr int monomial_count(int D) { return (D + 1) * (D + 2) * (D + 3) / 6; }

/// The same enumeration as MonomialTable for a degree known at compile time, so that the
/// monomials of a hit point are computed in fully unrolled code.
template <int D>
struct FixedMonomials {
  static constexpr int kCount = monomial_count(D);
  std::array<int, kCount> parent{};
  std::array<int, kCount> axis{};
  constexpr FixedMonomials() {
    constexpr int n = D + 1;
    std::array<int, n * n * n> index{};
    int pos = 0;
    for (int total = 0; total <= D; ++total) {
      for (int i = total; i >= 0; --i)
        for (int j = total - i; j >= 0; --j) {
          const int k = total - i - j;
          index[static_cast<size_t>((i * n + j) * n + k)] = pos;
          if (total > 0) {
            const int a = i > 0 ? 0 : (j > 0 ? 1 : 2);
            const int pi = i - (a == 0), pj = j - (a == 1), pk = k - (a == 2);
            parent[static_cast<size_t>(pos)] = index[static_cast<size_t>((pi * n + pj) * n + pk)];
            axis[static_cast<size_t>(pos)] = a;
          }
          ++pos;
        }
    }
  }
};

/// mono[m] = v^monomial m for every monomial of degree ≤ D, unrolled.
template <int D>
void monomials_fixed(const double* v, double* mono) {
  static constexpr FixedMonomials<D> t{};
  mono[0] = 1;
  [&]<size_t... I>(std::index_sequence<I...>) {
    ((mono[I + 1] = mono[t.parent[I + 1]] * v[t.axis[I + 1]]), ...);
  }(std::make_index_sequence<FixedMonomials<D>::kCount - 1>{});
}

/// coeffs[k] = Σ_j row[k(k+1)/2 + j] s^j for k ≤ d: each coefficient of the ray's
/// polynomial from its polynomial in s (Horner), unrolled when D > 0. Returns the rounding
/// band Σ_k band_coeffs[k] x^k (see rounding_band), evaluated alongside.
template <int D>
double restrict_in_row(const double* row, const double* band_coeffs, int d_, double s, double x,
                       double* coeffs) {
  const int d = D > 0 ? D : d_;
  double band = band_coeffs[d];
  for (int k = 0, offset = 0; k <= d; offset += ++k) {
    double v = row[offset + k];
    for (int j = k - 1; j >= 0; --j) v = std::fma(v, s, row[offset + j]);
    coeffs[k] = v;
  }
  for (int k = d - 1; k >= 0; --k) band = std::fma(band, x, band_coeffs[k]);
  return band;
}

#if defined(__AVX2__) && defined(__FMA__)
/// restrict_in_row and shift_to_unit for four rays at once, lane by lane the same operations
/// (so the same bits) as the scalar code: coeffs[k] and g[k] hold the four rays' k-th
/// coefficients. Lanes whose clip is empty compute garbage that is never used.
/// `row` and `band_coeffs` are restrict_in_row's, each coefficient in four lanes.
template <int D>
inline __m256d restrict_and_shift4(const double (*row)[4], const double (*band_coeffs)[4],
                                   __m256d s, __m256d x, __m256d t0, __m256d t1,
                                   __m256d* coeffs, __m256d* g) {
  __m256d band = _mm256_load_pd(band_coeffs[D]);
  for (int k = 0, offset = 0; k <= D; offset += ++k) {
    __m256d v = _mm256_load_pd(row[offset + k]);
    for (int j = k - 1; j >= 0; --j) v = _mm256_fmadd_pd(v, s, _mm256_load_pd(row[offset + j]));
    coeffs[k] = v;
    g[k] = v;
  }
  for (int k = D - 1; k >= 0; --k) band = _mm256_fmadd_pd(band, x, _mm256_load_pd(band_coeffs[k]));
  for (int i = 0; i < D; ++i)
    for (int k = D - 1; k >= i; --k) g[k] = _mm256_fmadd_pd(t0, g[k + 1], g[k]);
  const __m256d w = _mm256_sub_pd(t1, t0);
  __m256d wk = w;
  for (int k = 1; k <= D; ++k) {
    g[k] = _mm256_mul_pd(g[k], wk);
    wk = _mm256_mul_pd(wk, w);
  }
  return band;
}

// Halvings of the clipped segment that prepare4 searches for all four rays of a packet. Each
// level proves more misses but costs the packets that reach it; on the reference scenes the
// gain flattens out at 4 (a picture of Barth's sextic: 3% fewer instructions than with 3).
constexpr int kHullLevels = 4;

/// Which lanes of a sequence of coefficients so far all lie above the band (`above`), or all
/// below it (`below`): the convex hull test of RootFinder, one coefficient at a time.
struct HullTest4 {
  __m256d above, below;
  void first(__m256d b, __m256d band, __m256d lower) {
    above = _mm256_cmp_pd(b, band, _CMP_GT_OQ);
    below = _mm256_cmp_pd(b, lower, _CMP_LT_OQ);
  }
  void next(__m256d b, __m256d band, __m256d lower) {
    above = _mm256_and_pd(above, _mm256_cmp_pd(b, band, _CMP_GT_OQ));
    below = _mm256_and_pd(below, _mm256_cmp_pd(b, lower, _CMP_LT_OQ));
  }
  __m256d beyond() const { return _mm256_or_pd(above, below); }
};

/// The lanes among `open` that RootFinder's search of Bernstein coefficients b (destroyed)
/// proves rootless within kLevels halvings: the convex hull lies beyond the band on the
/// interval, or on every part it is split into. Lane by lane the same operations as the
/// scalar search (split_half: de Casteljau at 1/2), so the same decisions. A part is split
/// only while some lane of `open` may still be rootless there (its end values agree in sign:
/// else it has a root), and its right half only looked at for the lanes whose left half is
/// rootless. Inlined whole, so that the coefficients stay in registers.
template <int D, int kLevels>
[[gnu::always_inline]] inline int rootless4(__m256d* b, __m256d band, __m256d lower, int open) {
  HullTest4 hull;
  hull.first(b[0], band, lower);
#pragma GCC unroll 16
  for (int k = 1; k <= D; ++k) hull.next(b[k], band, lower);
  const int beyond = _mm256_movemask_pd(hull.beyond());
  if constexpr (kLevels == 0) {
    return beyond;
  } else {
    open &= ~beyond & ~_mm256_movemask_pd(_mm256_xor_pd(b[0], b[D]));  // sign bits
    if (open == 0) return beyond;
    const __m256d half = _mm256_set1_pd(0.5);
    __m256d left[D + 1], right[D + 1];
#pragma GCC unroll 16
    for (int r = 0; r <= D; ++r) {
      left[r] = b[0];
      right[D - r] = b[D - r];
#pragma GCC unroll 16
      for (int i = 0; i < D - r; ++i) b[i] = _mm256_mul_pd(half, _mm256_add_pd(b[i], b[i + 1]));
    }
    const int left_rootless = rootless4<D, kLevels - 1>(left, band, lower, open) & open;
    if (left_rootless == 0) return beyond;
    return beyond |
           (left_rootless & rootless4<D, kLevels - 1>(right, band, lower, left_rootless));
  }
}

/// The lanes among `lanes` of four rays (g as made by shift_to_unit, a ray per lane) that
/// RootFinder's search on the unit interval with no guess proves rootless in its first
/// kHullLevels halvings (see rootless4), from the same Bernstein coefficients (the operations
/// of to_bernstein). Nearly all rays that meet the clip volume but miss the surface end here,
/// before any scalar work (96–97% of them on the reference scenes). A guess would only
/// reorder the search of a ray with a root.
template <int D>
inline int hull_misses4(const __m256d* g, __m256d band, int lanes) {
  // to_bernstein on [0, 1]: b_k = g_k / C(D, k), then b_i = Σ_k C(i, k) b_k by repeated sums.
  __m256d b[D + 1];
  b[0] = g[0];
#pragma GCC unroll 16
  for (int k = 1; k <= D; ++k)
    b[k] = _mm256_mul_pd(g[k],
                         _mm256_set1_pd(detail::kInverseBinomials[D][static_cast<size_t>(k)]));
#pragma GCC unroll 16
  for (int i = 0; i < D; ++i)
#pragma GCC unroll 16
    for (int k = D; k > i; --k) b[k] = _mm256_add_pd(b[k], b[k - 1]);
  const __m256d lower = _mm256_sub_pd(_mm256_setzero_pd(), band);
  return rootless4<D, kHullLevels>(b, band, lower, lanes) & lanes;
}
#endif

/// The derivatives of G at t·(base + s·step) along the ray (a), the row's step (b) and the
/// row's plane normal (c) (see SurfaceRayCaster::Impl::row_gradient) from the ray's
/// polynomial f, the row's derivative in s and the row's ∇G·n, and the derivative of the
/// rounding band at x (e); unrolled when D > 0.
template <int D>
void row_derivatives(const double* f, const double* row_ds, const double* normal_row,
                     const double* band_coeffs, int d_, double s, double t, double x,
                     double* abce) {
  const int d = D > 0 ? D : d_;
  double a = 0, b = 0, c = 0, e = 0;
  for (int k = d; k >= 1; --k) {
    a = std::fma(a, t, k * f[k]);
    e = std::fma(e, x, k * band_coeffs[k]);
    const double* r = row_ds + k * (k - 1) / 2;
    double v = r[k - 1];
    for (int j = k - 2; j >= 0; --j) v = std::fma(v, s, r[j]);
    b = std::fma(b, t, v);
  }
  for (int k = d - 1; k >= 0; --k) {
    const double* r = normal_row + k * (k + 1) / 2;
    double v = r[k];
    for (int j = k - 1; j >= 0; --j) v = std::fma(v, s, r[j]);
    c = std::fma(c, t, v);
  }
  abce[0] = a;
  abce[1] = b;
  abce[2] = c;
  abce[3] = e;
}

/// A monomial of the partial derivatives of F: its position in a MonomialTable and its
/// coefficients in ∂F/∂x, ∂F/∂y, ∂F/∂z and a zero, four lanes summed as one vector.
struct GradientTerm {
  size_t position;
  Eigen::Matrix<double, 4, 1, Eigen::DontAlign> c;
};

/// g = (∂F/∂x, ∂F/∂y, ∂F/∂z) from the monomials of a point. Two sums, so that consecutive
/// multiply-adds do not wait for each other.
inline void sparse_gradient(const std::vector<GradientTerm>& terms, const double* mono,
                            double* g) {
  Eigen::Vector4d even = Eigen::Vector4d::Zero(), odd = Eigen::Vector4d::Zero();
  size_t i = 0;
  for (; i + 1 < terms.size(); i += 2) {
    even += terms[i].c * mono[terms[i].position];
    odd += terms[i + 1].c * mono[terms[i + 1].position];
  }
  if (i < terms.size()) even += terms[i].c * mono[terms[i].position];
  for (int k = 0; k < 3; ++k) g[k] = even[k] + odd[k];
}

/// Every monomial x^i y^j z^k of degree ≤ D in graded order (degree, then descending i, j),
/// each one the product of an earlier one (`parent`) and one variable (`axis`): the monomials
/// of a point are then one multiplication each.
struct MonomialTable {
  std::vector<int> parent;
  std::vector<int> axis;
  std::vector<int> index;  // (i, j, k) → position, at (i·(D+1) + j)·(D+1) + k
  int D = 0;

  explicit MonomialTable(int degree) : D(degree) {
    const int n = D + 1;
    index.assign(static_cast<size_t>(n) * n * n, -1);
    for (int total = 0; total <= D; ++total) {
      for (int i = total; i >= 0; --i)
        for (int j = total - i; j >= 0; --j) {
          const int k = total - i - j;
          const int pos = static_cast<int>(parent.size());
          index[static_cast<size_t>((i * n + j) * n + k)] = pos;
          if (total == 0) {
            parent.push_back(-1);
            axis.push_back(0);
          } else {
            // Divide by the first variable present: x if i > 0, else y, else z.
            const int a = i > 0 ? 0 : (j > 0 ? 1 : 2);
            const int pi = i - (a == 0), pj = j - (a == 1), pk = k - (a == 2);
            parent.push_back(index[static_cast<size_t>((pi * n + pj) * n + pk)]);
            axis.push_back(a);
          }
        }
    }
  }
  int at(int i, int j, int k) const {
    const int n = D + 1;
    return index[static_cast<size_t>((i * n + j) * n + k)];
  }
  size_t size() const { return parent.size(); }

  /// mono[m] = v^monomial m (size() entries).
  void evaluate(const Vec3& v, double* mono) const {
    const double x[3] = {v.x(), v.y(), v.z()};
    switch (D) {
      case 1: return monomials_fixed<1>(x, mono);
      case 2: return monomials_fixed<2>(x, mono);
      case 3: return monomials_fixed<3>(x, mono);
      case 4: return monomials_fixed<4>(x, mono);
      case 5: return monomials_fixed<5>(x, mono);
      case 6: return monomials_fixed<6>(x, mono);
      default: break;
    }
    // Local pointers: the stores to `mono` could otherwise alias the tables' storage.
    const int* par = parent.data();
    const int* ax = axis.data();
    mono[0] = 1;
    for (size_t m = 1; m < size(); ++m) mono[m] = mono[par[m]] * x[ax[m]];
  }
};

/// Bracketed refinement of a sign change of a scalar function of t (Illinois method).
template <class F>
double refine_sign_change(F&& f, double a, double b, double fa, double fb, double tol) {
  int retained = 0;
  for (int iter = 0; iter < 100 && b - a > tol; ++iter) {
    double m = (a * fb - b * fa) / (fb - fa);
    if (!(m > a && m < b)) m = 0.5 * (a + b);
    const double fm = f(m);
    if (fm == 0) return m;
    if (!std::isfinite(fm)) {
      // Undefined inside the bracket: bisect on the side that keeps a defined end.
      b = m;
      continue;
    }
    if ((fm > 0) == (fa > 0)) {
      a = m;
      fa = fm;
      if (retained == 1) fb *= 0.5;
      retained = 1;
    } else {
      b = m;
      fb = fm;
      if (retained == -1) fa *= 0.5;
      retained = -1;
    }
  }
  return 0.5 * (a + b);
}

}  // namespace

struct SurfaceRayCaster::Impl {
  Surface surface;
  Vec3 eye;
  RaycastOptions options;
  Evaluator evaluator;
  bool exact = false;
  int degree = 0;
  // Polynomial path. ∂F/∂x, ∂F/∂y, ∂F/∂z from F's own terms (well conditioned near the
  // surface, unlike the translated form), dense over the monomials of degree < degree.
  MonomialTable derivative_monomials{0};
  std::vector<GradientTerm> derivative;  // the monomials of the derivatives, in order
  std::vector<double> gradient_bound;  // [k]: Σ |coefficient| over degree k of all three
  std::vector<double> powers;          // scratch: monomials of a hit point
  // With bounds[k] the sum of the coefficients of degree k of |F| translated by |eye|,
  // bounds[k]·max|d_i|^k ≥ |G_k(d)| for every direction d and bounds the rounding error scale
  // of G_k. The rounding band of a ray is rounding_band(bounds, t1·max|d_i|), a polynomial in
  // t1·max|d_i| with these coefficients.
  std::array<double, kN> band_coeffs{};
  RootFinder finder;
  std::array<double, kN> coeffs{};

  // For the rows: every monomial of degree ≤ degree (row_monomials), as a polynomial in s at
  // base + s·step, its deg + 1 coefficients at mono_poly[mono_offset[m]]; G's terms and
  // ∇G = (∂G/∂x, ∂G/∂y, ∂G/∂z) (one polynomial with vector coefficients, degree − 1) by
  // their monomials' positions.
  MonomialTable row_monomials{0};
  std::vector<int> mono_offset;
  std::vector<double> mono_poly;
  struct RowTerm {
    int position, degree;
    double c;
  };
  struct PartialsTerm {
    int position, degree;
    Vec3 c;
  };
  std::vector<RowTerm> row_terms;
  std::vector<PartialsTerm> translated_gradient;

  // The current row: directions base + s·step.
  Vec3 base = Vec3::UnitX(), step = Vec3::Zero();
  // Exact path: G_k(base + s·step) = Σ_j row[k(k+1)/2 + j] s^j.
  std::array<double, kN * (kN + 1) / 2> row{};
  // Normals along the row (see row_gradient): the derivative in s of row, ∂G_k/∂s =
  // Σ_j row_ds[k(k−1)/2 + j] s^j (k ≥ 1); the normal of the row's plane, n = base × step; and
  // the homogeneous parts of ∇G·n, (∇G·n)_k(base + s·step) = Σ_j normal_row[k(k+1)/2 + j] s^j.
  std::array<double, kN * (kN + 1) / 2> row_ds{};
  std::array<double, kN * (kN + 1) / 2> normal_row{};
  Vec3 row_normal = Vec3::Zero();
  double row_dot = 0, row_ss = 0, row_inverse_nn = 0;  // base·step, |step|², 1 / |n|²
  bool has_row_normals = false;  // false for a row of one ray (step = 0)
  // The clip along the row's rays (as Clip::ray_interval, with its terms expanded in s).
  struct SphereRow {
    double a0, a1, a2;  // |d|² = a0 + 2 a1 s + a2 s²
    double b0, b1;      // (eye − centre)·d = b0 + b1 s
    double c;           // |eye − centre|² − radius²
  };
  struct PlaneRow {
    double n0, n1;  // normal·d = n0 + n1 s
    double g;       // normal·eye − offset
  };
  std::vector<SphereRow> sphere_rows;
  std::vector<PlaneRow> plane_rows;
  double s_min = 0, s_max = 0;  // see find_row_extent

  // Interval path.
  std::unique_ptr<detail::IntervalEvaluator> intervals;
  struct Segment {
    double a, b;
  };
  std::vector<Segment> segments;  // scratch: the subdivision stack

  Impl(const Surface& s, const Vec3& e, const RaycastOptions& o)
      : surface(s), eye(e), options(o), evaluator(s.field), finder(o.roots) {
    (void)surface.bounds();  // throws BadInput naming the surface when the clip is unbounded
    const Field& field = surface.field;
    exact = !o.force_interval && field.is_expandable() &&
            field.degree() <= RootFinder::kMaxDegree;
    if (exact) {
      const Polynomial poly = field.polynomial();
      degree = std::max(poly.degree(), 0);
      {
        // G(p) = F(eye + p).
        const std::vector<Monomial> translated = poly.translated(eye).terms();
        row_monomials = MonomialTable(degree);
        const MonomialTable& table = row_monomials;
        // The table's graded order: (total + 1)(total + 2)/2 monomials of each degree.
        std::vector<int> degree_of;
        int offset = 0;
        for (int total = 0; total <= degree; ++total)
          for (int m = 0; m < (total + 1) * (total + 2) / 2; ++m) {
            degree_of.push_back(total);
            mono_offset.push_back(offset);
            offset += total + 1;
          }
        mono_poly.assign(static_cast<size_t>(offset), 0.0);
        std::vector<Vec3> dense(table.size(), Vec3::Zero());
        for (const Monomial& m : translated) {
          row_terms.push_back({table.at(m.i, m.j, m.k), m.degree(), m.c});
          if (m.i > 0) dense[static_cast<size_t>(table.at(m.i - 1, m.j, m.k))].x() = m.i * m.c;
          if (m.j > 0) dense[static_cast<size_t>(table.at(m.i, m.j - 1, m.k))].y() = m.j * m.c;
          if (m.k > 0) dense[static_cast<size_t>(table.at(m.i, m.j, m.k - 1))].z() = m.k * m.c;
        }
        for (size_t m = 0; m < dense.size(); ++m)
          if (!dense[m].isZero())
            translated_gradient.push_back({static_cast<int>(m), degree_of[m], dense[m]});
      }
      derivative_monomials = MonomialTable(std::max(degree - 1, 0));
      gradient_bound.assign(static_cast<size_t>(derivative_monomials.D + 1), 0.0);
      // Polynomial's terms are unique, so each derivative gets each monomial at most once.
      std::vector<GradientTerm> dense(derivative_monomials.size());
      for (size_t m = 0; m < dense.size(); ++m) dense[m] = {m, Eigen::Vector4d::Zero()};
      auto add_derivative = [&](int axis, int i, int j, int k, double c) {
        dense[static_cast<size_t>(derivative_monomials.at(i, j, k))].c[axis] = c;
        gradient_bound[static_cast<size_t>(i + j + k)] += std::abs(c);
      };
      std::vector<Monomial> abs_terms;
      for (const Monomial& m : poly.terms()) {
        abs_terms.push_back({m.i, m.j, m.k, std::abs(m.c)});
        if (m.i > 0) add_derivative(0, m.i - 1, m.j, m.k, m.i * m.c);
        if (m.j > 0) add_derivative(1, m.i, m.j - 1, m.k, m.j * m.c);
        if (m.k > 0) add_derivative(2, m.i, m.j, m.k - 1, m.k * m.c);
      }
      for (const GradientTerm& term : dense)
        if (!term.c.isZero()) derivative.push_back(term);
      const Polynomial gb = Polynomial(abs_terms).translated(eye.cwiseAbs());
      std::array<double, kN> bounds{};
      for (const Monomial& m : gb.terms()) bounds[static_cast<size_t>(m.degree())] += m.c;
      // rounding_band's polynomial in t_max, coefficient by coefficient.
      std::vector<double> unit(static_cast<size_t>(degree + 1), 0.0);
      for (int k = 0; k <= degree; ++k) {
        unit[static_cast<size_t>(k)] = bounds[static_cast<size_t>(k)];
        band_coeffs[static_cast<size_t>(k)] = rounding_band(unit, 1.0);
        unit[static_cast<size_t>(k)] = 0;
      }
      powers.assign(derivative_monomials.size(), 0.0);
      if (degree <= kPacketDegree) {
        broadcast(band_coeffs.data(), degree + 1, band4);
        for (int k = 0; k <= degree; ++k) {
          const double v = k * band_coeffs[static_cast<size_t>(k)];
          broadcast(&v, 1, k_band4 + k);
        }
        broadcast(gradient_bound.data(), static_cast<int>(gradient_bound.size()), gradient_bound4);
      }
    } else {
      intervals = std::make_unique<detail::IntervalEvaluator>(field);
    }
    sphere_rows.resize(surface.clip.spheres.size());
    plane_rows.resize(surface.clip.planes.size());
  }

  void begin_row(const Vec3& row_base, const Vec3& row_step) {
    packet_size = 0;
    packet_ready = false;
    packet_hit_bits = packet_done_bits = 0;
    base = row_base;
    step = row_step;
    for (size_t i = 0; i < sphere_rows.size(); ++i) {
      const SphereClip& sphere = surface.clip.spheres[i];
      const Vec3 oc = eye - sphere.center;
      sphere_rows[i] = {base.squaredNorm(),
                        base.dot(step),
                        step.squaredNorm(),
                        oc.dot(base),
                        oc.dot(step),
                        oc.squaredNorm() - sphere.radius * sphere.radius};
    }
    for (size_t i = 0; i < plane_rows.size(); ++i) {
      const HalfSpaceClip& plane = surface.clip.planes[i];
      plane_rows[i] = {plane.normal.dot(base), plane.normal.dot(step),
                       plane.normal.dot(eye) - plane.offset};
    }
    find_row_extent();
    if (exact) expand_row();
  }

  /// [s_min, s_max] ⊇ the s whose rays meet every clip sphere: with the eye outside a
  /// sphere, the discriminant of clip() is a quadratic A s² + 2B s + C that is nonnegative
  /// on an interval when A < 0. Widened well beyond rounding; clip() decides inside it.
  void find_row_extent() {
    s_min = -std::numeric_limits<double>::infinity();
    s_max = std::numeric_limits<double>::infinity();
    for (const SphereRow& r : sphere_rows) {
      if (!(r.c > 0)) continue;  // the eye is inside: every ray meets the sphere
      const double A = r.b1 * r.b1 - r.c * r.a2, B = r.b0 * r.b1 - r.c * r.a1;
      const double C = r.b0 * r.b0 - r.c * r.a0;
      if (!(A < 0)) continue;  // no bound from this sphere (a row of one ray, step = 0)
      const double disc = B * B - A * C;
      if (disc < -1e-12 * (B * B + std::abs(A * C))) {  // the row's plane misses the sphere
        s_min = std::numeric_limits<double>::infinity();
        s_max = -s_min;
        return;
      }
      const double q = -(B + std::copysign(std::sqrt(std::max(disc, 0.0)), B));
      double lo = q / A, hi = q != 0 ? C / q : -B / A;
      if (lo > hi) std::swap(lo, hi);
      const double margin = 1e-7 * (1 + std::abs(lo) + std::abs(hi));
      s_min = std::max(s_min, lo - margin);
      s_max = std::min(s_max, hi + margin);
    }
  }

  /// row = G restricted to the row's directions: each term c·x^i y^j z^l of G becomes
  /// c·(bx + s·sx)^i (by + s·sy)^j (bz + s·sz)^l, multiplied out in s. With step = 0 (a
  /// single ray) only the constant terms are formed.
  void expand_row() {
    const int n = degree + 1;
    const bool flat = step.isZero();
    // Each monomial as a polynomial in s: its parent's times (base_a + s·step_a), so every
    // monomial costs deg + 1 multiply-adds, and each term of G or ∇G·n then deg + 1 more.
    const int* parent = row_monomials.parent.data();
    const int* axis = row_monomials.axis.data();
    const int* offset = mono_offset.data();
    double* poly = mono_poly.data();
    poly[0] = 1;
    // Graded order: the monomials of degree k start at k(k+1)(k+2)/6 (`next` for k + 1).
    for (int m = 1, k = 1, next = 4; m < static_cast<int>(row_monomials.size()); ++m) {
      if (m == next) {
        ++k;
        next += (k + 1) * (k + 2) / 2;
      }
      const double* p = poly + offset[parent[m]];
      double* q = poly + offset[m];
      const double b = base[axis[m]], st = step[axis[m]];
      q[0] = p[0] * b;
      if (flat) continue;  // a single ray needs the constant coefficients only
      for (int j = 1; j < k; ++j) q[j] = p[j] * b + p[j - 1] * st;
      q[k] = p[k - 1] * st;
    }
    auto add_term = [&](int position, int k, double c, double* out) {
      const double* p = poly + offset[position];
      out += k * (k + 1) / 2;
      for (int j = 0; j <= (flat ? 0 : k); ++j) out[j] += c * p[j];
    };
    std::fill_n(row.begin(), n * (n + 1) / 2, 0.0);
    for (const RowTerm& t : row_terms) add_term(t.position, t.degree, t.c, row.data());
    const bool packets = degree <= kPacketDegree;
    if (packets) broadcast(row.data(), n * (n + 1) / 2, row4);
    has_row_normals = !flat;
    if (!has_row_normals) return;
    for (int k = 1; k <= degree; ++k)
      for (int j = 0; j < k; ++j)
        row_ds[static_cast<size_t>(k * (k - 1) / 2 + j)] =
            (j + 1) * row[static_cast<size_t>(k * (k + 1) / 2 + j + 1)];
    row_normal = base.cross(step);
    row_dot = base.dot(step);
    row_ss = step.squaredNorm();
    row_inverse_nn = 1 / row_normal.squaredNorm();
    std::fill_n(normal_row.begin(), degree * (degree + 1) / 2, 0.0);
    for (const PartialsTerm& t : translated_gradient)
      add_term(t.position, t.degree, t.c.dot(row_normal), normal_row.data());
    if (packets) {
      broadcast(row_ds.data(), degree * (degree + 1) / 2, row_ds4);
      broadcast(normal_row.data(), degree * (degree + 1) / 2, normal_row4);
    }
  }

  /// ∇F at the hit eye + t·(base + s·step) of the current ray from the row's expansions
  /// (its coefficients must be in `coeffs`): the derivatives along the ray d = base + s·step,
  /// along step and along n = base × step are polynomials in t whose coefficients are
  /// polynomials in s, a few dozen multiply-adds instead of evaluating ∇F's terms. They are
  /// those of G, translated to the eye, so they round on the scale of G's terms: `error`
  /// receives a bound on the error of the result (scaled like it), from the derivative of the
  /// rounding band. False for a row of one ray.
  bool row_gradient(double s, double t, Vec3& g, double& error) const {
    if (!has_row_normals) return false;
    // Fused multiply-adds in the order complete4 uses, so that both give the same bits.
    const double dx = std::fma(s, step.x(), base.x()), dy = std::fma(s, step.y(), base.y()),
                 dz = std::fma(s, step.z(), base.z());
    const double x = t * std::max({std::abs(dx), std::abs(dy), std::abs(dz)});
    // a = ∇G·d = f'(t); b = ∇G·step = Σ_k t^(k−1) ∂G_k/∂s; c = ∇G·n = Σ_k t^k (∇G·n)_k;
    // e: the derivative of the rounding band.
    double abce[4];
    const double *f = ray_coeffs, *ds_row = row_ds.data(), *h = normal_row.data(),
                 *bc = band_coeffs.data();
    switch (degree) {
      case 1: row_derivatives<1>(f, ds_row, h, bc, degree, s, t, x, abce); break;
      case 2: row_derivatives<2>(f, ds_row, h, bc, degree, s, t, x, abce); break;
      case 3: row_derivatives<3>(f, ds_row, h, bc, degree, s, t, x, abce); break;
      case 4: row_derivatives<4>(f, ds_row, h, bc, degree, s, t, x, abce); break;
      case 5: row_derivatives<5>(f, ds_row, h, bc, degree, s, t, x, abce); break;
      case 6: row_derivatives<6>(f, ds_row, h, bc, degree, s, t, x, abce); break;
      default: row_derivatives<0>(f, ds_row, h, bc, degree, s, t, x, abce); break;
    }
    const double a = abce[0], b = abce[1], c = abce[2];
    // With the dual basis of (d, step, n): ∇ = [a (|step|² d − (d·step) step)
    // + b (|d|² step − (d·step) d) + c n] / |n|², |n|² = |d|²|step|² − (d·step)².
    // Plain scalars: Eigen's 3-vector expressions cost several times as much here.
    const double dd = squared_norm(dx, dy, dz), ds = std::fma(s, row_ss, row_dot);
    const double p = std::fma(a, row_ss, -(b * ds)) * row_inverse_nn,
                 q = std::fma(b, dd, -(a * ds)) * row_inverse_nn, r = c * row_inverse_nn;
    g = Vec3(std::fma(r, row_normal.x(), std::fma(q, step.x(), p * dx)),
             std::fma(r, row_normal.y(), std::fma(q, step.y(), p * dy)),
             std::fma(r, row_normal.z(), std::fma(q, step.z(), p * dz)));
    // Each directional derivative along a unit vector rounds by at most the derivative of the
    // band; the dual basis of the row's (well-conditioned) basis scales that by about
    // |d|²|step|² / |n|², which a factor 4 covers.
    error = 4 * abce[3] * dd * row_ss * row_inverse_nn;
    return true;
  }

  Vec3 direction(double s) const { return base + s * step; }

  /// The parameter interval [t0, t1] of the row's ray at s inside the clip (t ≥ 0); false
  /// when it misses. The same stable formulas as Clip::ray_interval.
  bool clip(double s, double& t0, double& t1) const {
    t0 = 0;
    t1 = std::numeric_limits<double>::infinity();
    // Fused multiply-adds in the order prepare4 uses, so that both give the same bits.
    for (const SphereRow& r : sphere_rows) {
      const double a = std::fma(s, std::fma(s, r.a2, 2 * r.a1), r.a0);
      const double b = std::fma(s, r.b1, r.b0);
      const double disc = std::fma(b, b, -(a * r.c));
      if (disc < 0) return false;
      const double sq = std::sqrt(disc);
      const double qv = -(b + std::copysign(sq, b));
      double r0 = qv / a, r1 = qv != 0 ? r.c / qv : -b / a;
      if (r0 > r1) std::swap(r0, r1);
      t0 = std::max(t0, r0);
      t1 = std::min(t1, r1);
    }
    for (const PlaneRow& r : plane_rows) {
      const double nd = std::fma(s, r.n1, r.n0);
      if (nd == 0) {
        if (r.g > 0) return false;
        continue;
      }
      const double t = -r.g / nd;
      if (nd > 0)
        t1 = std::min(t1, t);
      else
        t0 = std::max(t0, t);
    }
    return t0 < t1;
  }

  /// The first root of f(t) = G(t·(base + s·step)) on [t0, t1] (NaN: none); `band`
  /// receives the rounding band used.
  double exact_hit(double s, double t0, double t1, const RootGuess& guess, double& band) {
    // A monomial of degree k in the direction's components is at most max|d_i|^k. The
    // expansion in s rounds relative to (|base_i| + |s||step_i|)^k instead, but its error
    // stays far below the band (under 2% for the catalog's scenes across whole pictures).
    const double x = t1 * max_abs_direction(s);
    const double* r = row.data();
    const double* b = band_coeffs.data();
    double* c = coeffs.data();
    ray_coeffs = c;
    switch (degree) {
      case 1: band = restrict_in_row<1>(r, b, degree, s, x, c); break;
      case 2: band = restrict_in_row<2>(r, b, degree, s, x, c); break;
      case 3: band = restrict_in_row<3>(r, b, degree, s, x, c); break;
      case 4: band = restrict_in_row<4>(r, b, degree, s, x, c); break;
      case 5: band = restrict_in_row<5>(r, b, degree, s, x, c); break;
      case 6: band = restrict_in_row<6>(r, b, degree, s, x, c); break;
      default: band = restrict_in_row<0>(r, b, degree, s, x, c); break;
    }
    return finder.find_first_root(std::span<const double>(c, static_cast<size_t>(degree + 1)),
                                  t0, t1, band, guess);
  }

  /// max_i |base_i + s·step_i|, with fused multiply-adds as in prepare4.
  double max_abs_direction(double s) const {
    return std::max({std::abs(std::fma(s, step.x(), base.x())),
                     std::abs(std::fma(s, step.y(), base.y())),
                     std::abs(std::fma(s, step.z(), base.z()))});
  }

  // A packet: four rays of the row (prepare_in_row). With AVX2 their straight-line parts are
  // done four at a time, bit for bit what the scalar code computes for each ray: the set-up
  // (clip, restriction, rounding band, shift to the clipped interval) and the first levels of
  // the isolation (hull_misses4) by prepare4, and the normals of their hits (packet_hits) by
  // complete4. The rest of the isolation stays per ray.
  // packet_g[i]: lane i's g (see shift_to_unit); packet_ck[k][i]: the k-th coefficient of lane
  // i's f; packet_open[i]: lane i's ray meets the clip volume and is not known to miss. The
  // lanes' hits: parameters, sides and whether each ray was cast and hit (packet_hit_bits);
  // hits completed at once (rays not set up here) in packet_done.
  std::array<double, 4> packet_s{};
  std::array<double, 4> packet_t0{}, packet_t1{}, packet_band{};
  std::array<bool, 4> packet_open{};
  int packet_full_bits = 0;  // lanes whose f has a nonzero leading coefficient
  int packet_size = 0;       // 4 after prepare_in_row, else 0
  int packet_next = 0;       // the lane packet_lane tries first
  bool packet_ready = false;  // the lanes are set up by prepare4
  alignas(32) double packet_g[4][kN];
  alignas(32) double packet_ck[kN][4];
  const double* ray_coeffs = coeffs.data();  // the current ray's f (see row_gradient)
  int cast_lane = -1;  // the packet's lane the last cast took, or -1
  // The row's coefficients that the packets use, each in all four lanes (loaded with the
  // multiply-adds rather than broadcast in each packet): row, row_ds, normal_row, the band's
  // and k·band_coeffs[k], gradient_bound.
  static constexpr int kPacketDegree = 6;
  static constexpr int kPacketRow = (kPacketDegree + 1) * (kPacketDegree + 2) / 2;
  alignas(32) double row4[kPacketRow][4];
  alignas(32) double row_ds4[kPacketRow][4];
  alignas(32) double normal_row4[kPacketRow][4];
  alignas(32) double band4[kPacketDegree + 1][4];
  alignas(32) double k_band4[kPacketDegree + 1][4];
  alignas(32) double gradient_bound4[kPacketDegree][4];

  static void broadcast(const double* v, int n, double (*out)[4]) {
    for (int i = 0; i < n; ++i) out[i][0] = out[i][1] = out[i][2] = out[i][3] = v[i];
  }
  /// f of the packet's lane i, gathered into `coeffs`.
  const double* lane_coeffs(int i) {
    for (int k = 0; k <= degree; ++k)
      coeffs[static_cast<size_t>(k)] = packet_ck[k][static_cast<size_t>(i)];
    return coeffs.data();
  }
  alignas(32) std::array<double, 4> packet_t{}, packet_side{};
  int packet_hit_bits = 0, packet_done_bits = 0;
  std::array<SurfaceHit, 4> packet_done;

  /// See SurfaceRayCaster::prepare_in_row.
  int prepare(std::span<const double> s) {
    packet_size = 0;
    packet_ready = false;
    packet_hit_bits = packet_done_bits = 0;
    if (s.size() != 4) return 0;
    std::copy(s.begin(), s.end(), packet_s.begin());
    packet_size = 4;
    packet_next = 0;
#if defined(__AVX2__) && defined(__FMA__)
    if (!exact) return 0;
    switch (degree) {
      case 1: return prepare4<1>(s.data());
      case 2: return prepare4<2>(s.data());
      case 3: return prepare4<3>(s.data());
      case 4: return prepare4<4>(s.data());
      case 5: return prepare4<5>(s.data());
      case 6: return prepare4<6>(s.data());
      default: break;  // degrees above 6 are set up ray by ray
    }
#endif
    return 0;
  }

  /// first_hit_in_row: cast, and keep the hit for packet_hits when s is in the packet.
  double first_hit_in_row(double s, const RootGuess& guess) {
    int side = 0;
    const double t = cast(s, guess, side);
    const int lane = packet_ready ? cast_lane : packet_lane(s);
    if (lane < 0) return t;
    packet_next = lane + 1;
    if (std::isnan(t)) return t;
    const size_t i = static_cast<size_t>(lane);
    packet_hit_bits |= 1 << lane;
    if (packet_ready) {
      packet_t[i] = t;
      packet_side[i] = side;
    } else {
      // The ray's polynomial is not kept past the next ray: complete the hit now.
      complete(s, t, side, packet_done[i]);
      packet_done_bits |= 1 << lane;
    }
    return t;
  }

  /// The hits of the packet's rays that first_hit_in_row found (bit i: lane i hit).
  int packet_hits(SurfaceHit (&hits)[4]) {
    int remaining = packet_hit_bits & ~packet_done_bits;
#if defined(__AVX2__) && defined(__FMA__)
    if (remaining != 0 && packet_ready && has_row_normals) {
      switch (degree) {
        case 1: remaining &= ~complete4<1>(remaining, hits); break;
        case 2: remaining &= ~complete4<2>(remaining, hits); break;
        case 3: remaining &= ~complete4<3>(remaining, hits); break;
        case 4: remaining &= ~complete4<4>(remaining, hits); break;
        case 5: remaining &= ~complete4<5>(remaining, hits); break;
        case 6: remaining &= ~complete4<6>(remaining, hits); break;
        default: break;
      }
    }
#endif
    for (int i = 0; i < 4; ++i) {
      const size_t lane = static_cast<size_t>(i);
      if ((packet_done_bits >> i) & 1) hits[i] = packet_done[lane];
      if (!((remaining >> i) & 1)) continue;
      // Where the row's gradient is not used: ∇F from F's terms, as for single rays.
      ray_coeffs = lane_coeffs(i);
      complete(packet_s[lane], packet_t[lane], static_cast<int>(packet_side[lane]), hits[i]);
    }
    const int bits = packet_hit_bits;
    packet_hit_bits = packet_done_bits = 0;
    return bits;
  }

#if defined(__AVX2__) && defined(__FMA__)
  /// Sets up the packet (see above); returns the lanes that miss.
  template <int D>
  int prepare4(const double* sv) {
    const __m256d S = _mm256_loadu_pd(sv);
    const __m256d zero = _mm256_setzero_pd(), sign = _mm256_set1_pd(-0.0);
    __m256d t0 = zero, t1 = _mm256_set1_pd(std::numeric_limits<double>::infinity());
    __m256d miss = zero;  // all bits set in the lanes that miss
    for (const SphereRow& r : sphere_rows) {
      const __m256d c = _mm256_set1_pd(r.c);
      const __m256d a =
          _mm256_fmadd_pd(S, _mm256_fmadd_pd(S, _mm256_set1_pd(r.a2), _mm256_set1_pd(2 * r.a1)),
                          _mm256_set1_pd(r.a0));
      const __m256d b = _mm256_fmadd_pd(S, _mm256_set1_pd(r.b1), _mm256_set1_pd(r.b0));
      const __m256d disc = _mm256_fmsub_pd(b, b, _mm256_mul_pd(a, c));
      miss = _mm256_or_pd(miss, _mm256_cmp_pd(disc, zero, _CMP_LT_OQ));
      const __m256d sq = _mm256_sqrt_pd(disc);
      const __m256d signed_sq = _mm256_or_pd(_mm256_andnot_pd(sign, sq), _mm256_and_pd(sign, b));
      const __m256d qv = _mm256_xor_pd(sign, _mm256_add_pd(b, signed_sq));
      const __m256d r0 = _mm256_div_pd(qv, a);
      const __m256d r1 = _mm256_blendv_pd(_mm256_div_pd(_mm256_xor_pd(sign, b), a),
                                          _mm256_div_pd(c, qv),
                                          _mm256_cmp_pd(qv, zero, _CMP_NEQ_UQ));
      // As std::swap when r0 > r1 and std::max(t0, ·), std::min(t1, ·), NaNs included.
      t0 = _mm256_max_pd(_mm256_min_pd(r1, r0), t0);
      t1 = _mm256_min_pd(_mm256_max_pd(r0, r1), t1);
    }
    for (const PlaneRow& r : plane_rows) {
      const __m256d nd = _mm256_fmadd_pd(S, _mm256_set1_pd(r.n1), _mm256_set1_pd(r.n0));
      const __m256d parallel = _mm256_cmp_pd(nd, zero, _CMP_EQ_OQ);
      if (r.g > 0) miss = _mm256_or_pd(miss, parallel);
      const __m256d t = _mm256_div_pd(_mm256_set1_pd(-r.g), nd);
      const __m256d exits = _mm256_cmp_pd(nd, zero, _CMP_GT_OQ);
      t1 = _mm256_blendv_pd(t1, _mm256_min_pd(t, t1), exits);
      t0 = _mm256_blendv_pd(_mm256_max_pd(t, t0), t0, _mm256_or_pd(exits, parallel));
    }
    const __m256d inside = _mm256_andnot_pd(miss, _mm256_cmp_pd(t0, t1, _CMP_LT_OQ));
    const int inside_bits = _mm256_movemask_pd(inside);
    packet_ready = true;
    if (inside_bits == 0) {
      packet_open.fill(false);
      return 0xf;
    }
    const __m256d ax = _mm256_andnot_pd(
        sign, _mm256_fmadd_pd(S, _mm256_set1_pd(step.x()), _mm256_set1_pd(base.x())));
    const __m256d ay = _mm256_andnot_pd(
        sign, _mm256_fmadd_pd(S, _mm256_set1_pd(step.y()), _mm256_set1_pd(base.y())));
    const __m256d az = _mm256_andnot_pd(
        sign, _mm256_fmadd_pd(S, _mm256_set1_pd(step.z()), _mm256_set1_pd(base.z())));
    const __m256d x = _mm256_mul_pd(t1, _mm256_max_pd(_mm256_max_pd(ax, ay), az));
    __m256d c[D + 1], g[D + 1];
    const __m256d band = restrict_and_shift4<D>(row4, band4, S, x, t0, t1, c, g);
    _mm256_storeu_pd(packet_t0.data(), t0);
    _mm256_storeu_pd(packet_t1.data(), t1);
    _mm256_storeu_pd(packet_band.data(), band);
    store_lanes<D>(g, packet_g);
    for (int k = 0; k <= D; ++k) _mm256_store_pd(packet_ck[k], c[k]);
    packet_full_bits = _mm256_movemask_pd(_mm256_cmp_pd(c[D], _mm256_setzero_pd(), _CMP_NEQ_UQ));
    // Lanes of a lower degree are left to the general search, which trims the degree. The
    // scalar search splits the parts that hull_misses4 splits only when they are wider than
    // its tolerance: always, unless RootOptions::tolerance is raised to 2^(1 − kHullLevels).
    const bool same_splits = options.roots.tolerance < 2.0 / (1 << kHullLevels);
    const int open =
        inside_bits &
        ~(same_splits ? hull_misses4<D>(g, band, packet_full_bits & inside_bits) : 0);
    for (int i = 0; i < 4; ++i) packet_open[static_cast<size_t>(i)] = (open >> i) & 1;
    return ~open & 0xf;
  }

  /// complete for the lanes in `bits` where the row's gradient is used, four at once with
  /// the same operations; returns the lanes done.
  template <int D>
  int complete4(int bits, SurfaceHit (&hits)[4]) const {
    const __m256d sign = _mm256_set1_pd(-0.0), zero = _mm256_setzero_pd();
    const __m256d S = _mm256_loadu_pd(packet_s.data()), T = _mm256_load_pd(packet_t.data());
    const __m256d dx = _mm256_fmadd_pd(S, _mm256_set1_pd(step.x()), _mm256_set1_pd(base.x()));
    const __m256d dy = _mm256_fmadd_pd(S, _mm256_set1_pd(step.y()), _mm256_set1_pd(base.y()));
    const __m256d dz = _mm256_fmadd_pd(S, _mm256_set1_pd(step.z()), _mm256_set1_pd(base.z()));
    const __m256d px = _mm256_fmadd_pd(T, dx, _mm256_set1_pd(eye.x()));
    const __m256d py = _mm256_fmadd_pd(T, dy, _mm256_set1_pd(eye.y()));
    const __m256d pz = _mm256_fmadd_pd(T, dz, _mm256_set1_pd(eye.z()));
    // gradient_scale and the floor of kRelativeGradientFloor.
    const __m256d m = _mm256_max_pd(
        _mm256_max_pd(_mm256_andnot_pd(sign, px), _mm256_andnot_pd(sign, py)),
        _mm256_andnot_pd(sign, pz));
    __m256d bound = zero;
    for (size_t k = gradient_bound.size(); k-- > 0;)
      bound = _mm256_fmadd_pd(bound, m, _mm256_load_pd(gradient_bound4[k]));
    const __m256d floor = _mm256_mul_pd(_mm256_set1_pd(kRelativeGradientFloor), bound);
    // row_derivatives and row_gradient.
    const __m256d x = _mm256_mul_pd(
        T, _mm256_max_pd(
               _mm256_max_pd(_mm256_andnot_pd(sign, dx), _mm256_andnot_pd(sign, dy)),
               _mm256_andnot_pd(sign, dz)));
    __m256d a = zero, b = zero, c = zero, e = zero;
    for (int k = D; k >= 1; --k) {
      a = _mm256_fmadd_pd(a, T, _mm256_mul_pd(_mm256_set1_pd(k), _mm256_load_pd(packet_ck[k])));
      e = _mm256_fmadd_pd(e, x, _mm256_load_pd(k_band4[k]));
      const double(*r)[4] = row_ds4 + k * (k - 1) / 2;
      __m256d v = _mm256_load_pd(r[k - 1]);
      for (int j = k - 2; j >= 0; --j) v = _mm256_fmadd_pd(v, S, _mm256_load_pd(r[j]));
      b = _mm256_fmadd_pd(b, T, v);
    }
    for (int k = D - 1; k >= 0; --k) {
      const double(*r)[4] = normal_row4 + k * (k + 1) / 2;
      __m256d v = _mm256_load_pd(r[k]);
      for (int j = k - 1; j >= 0; --j) v = _mm256_fmadd_pd(v, S, _mm256_load_pd(r[j]));
      c = _mm256_fmadd_pd(c, T, v);
    }
    const __m256d ss = _mm256_set1_pd(row_ss), inn = _mm256_set1_pd(row_inverse_nn);
    const __m256d dd = _mm256_fmadd_pd(dz, dz, _mm256_fmadd_pd(dy, dy, _mm256_mul_pd(dx, dx)));
    const __m256d ds = _mm256_fmadd_pd(S, ss, _mm256_set1_pd(row_dot));
    const __m256d p = _mm256_mul_pd(_mm256_fmsub_pd(a, ss, _mm256_mul_pd(b, ds)), inn);
    const __m256d q = _mm256_mul_pd(_mm256_fmsub_pd(b, dd, _mm256_mul_pd(a, ds)), inn);
    const __m256d r = _mm256_mul_pd(c, inn);
    const __m256d gx = _mm256_fmadd_pd(r, _mm256_set1_pd(row_normal.x()),
                                       _mm256_fmadd_pd(q, _mm256_set1_pd(step.x()),
                                                       _mm256_mul_pd(p, dx)));
    const __m256d gy = _mm256_fmadd_pd(r, _mm256_set1_pd(row_normal.y()),
                                       _mm256_fmadd_pd(q, _mm256_set1_pd(step.y()),
                                                       _mm256_mul_pd(p, dy)));
    const __m256d gz = _mm256_fmadd_pd(r, _mm256_set1_pd(row_normal.z()),
                                       _mm256_fmadd_pd(q, _mm256_set1_pd(step.z()),
                                                       _mm256_mul_pd(p, dz)));
    const __m256d error = _mm256_mul_pd(
        _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(4.0), e), dd), ss), inn);
    // complete's test: in_open_range(|g|², max(square(margin·floor), square(accuracy·error))).
    const __m256d g2 = _mm256_fmadd_pd(gz, gz, _mm256_fmadd_pd(gy, gy, _mm256_mul_pd(gx, gx)));
    const __m256d mf = _mm256_mul_pd(_mm256_set1_pd(kRowGradientMargin), floor);
    const __m256d ae = _mm256_mul_pd(_mm256_set1_pd(kRowGradientAccuracy), error);
    const __m256d lo = _mm256_max_pd(_mm256_mul_pd(ae, ae), _mm256_mul_pd(mf, mf));
    const __m256d accept = _mm256_and_pd(
        _mm256_cmp_pd(g2, lo, _CMP_GT_OQ),
        _mm256_cmp_pd(g2, _mm256_set1_pd(std::numeric_limits<double>::infinity()), _CMP_LT_OQ));
    const int done = _mm256_movemask_pd(accept) & bits;
    if (done == 0) return 0;
    const __m256d gd = _mm256_fmadd_pd(gz, dz, _mm256_fmadd_pd(gy, dy, _mm256_mul_pd(gx, dx)));
    const __m256d k = _mm256_div_pd(
        _mm256_blendv_pd(_mm256_set1_pd(1.0), _mm256_set1_pd(-1.0),
                         _mm256_cmp_pd(gd, zero, _CMP_GT_OQ)),
        _mm256_sqrt_pd(g2));
    const __m256d side = _mm256_load_pd(packet_side.data());
    const __m256d front = _mm256_blendv_pd(_mm256_cmp_pd(gd, zero, _CMP_LT_OQ),
                                           _mm256_cmp_pd(side, zero, _CMP_GT_OQ),
                                           _mm256_cmp_pd(side, zero, _CMP_NEQ_OQ));
    const int front_bits = _mm256_movemask_pd(front);
    alignas(32) double out[6][4];
    _mm256_store_pd(out[0], px);
    _mm256_store_pd(out[1], py);
    _mm256_store_pd(out[2], pz);
    _mm256_store_pd(out[3], _mm256_mul_pd(k, gx));
    _mm256_store_pd(out[4], _mm256_mul_pd(k, gy));
    _mm256_store_pd(out[5], _mm256_mul_pd(k, gz));
    for (int i = 0; i < 4; ++i) {
      if (!((done >> i) & 1)) continue;
      SurfaceHit& h = hits[i];
      h.t = packet_t[static_cast<size_t>(i)];
      h.point = Vec3(out[0][i], out[1][i], out[2][i]);
      h.normal = Vec3(out[3][i], out[4][i], out[5][i]);
      h.front = (front_bits >> i) & 1;
      h.singular = false;
    }
    return done;
  }

  /// out[i][k] = v[k][i]: four coefficients at a time by a 4×4 transpose, the rest by lane.
  template <int D>
  static void store_lanes(const __m256d* v, double (*out)[kN]) {
    int k = 0;
    for (; k + 3 <= D; k += 4) {
      const __m256d a = _mm256_unpacklo_pd(v[k], v[k + 1]), b = _mm256_unpackhi_pd(v[k], v[k + 1]);
      const __m256d c = _mm256_unpacklo_pd(v[k + 2], v[k + 3]),
                    d = _mm256_unpackhi_pd(v[k + 2], v[k + 3]);
      _mm256_storeu_pd(out[0] + k, _mm256_permute2f128_pd(a, c, 0x20));
      _mm256_storeu_pd(out[1] + k, _mm256_permute2f128_pd(b, d, 0x20));
      _mm256_storeu_pd(out[2] + k, _mm256_permute2f128_pd(a, c, 0x31));
      _mm256_storeu_pd(out[3] + k, _mm256_permute2f128_pd(b, d, 0x31));
    }
    for (; k <= D; ++k) {
      const __m128d lo = _mm256_castpd256_pd128(v[k]), hi = _mm256_extractf128_pd(v[k], 1);
      _mm_storel_pd(out[0] + k, lo);
      _mm_storeh_pd(out[1] + k, lo);
      _mm_storel_pd(out[2] + k, hi);
      _mm_storeh_pd(out[3] + k, hi);
    }
  }
#endif

  /// The lane of the packet that holds the ray at s, or −1. Rays come in order, so the lane
  /// after the last one found is tried first.
  int packet_lane(double s) {
    if (packet_next < packet_size && packet_s[static_cast<size_t>(packet_next)] == s)
      return packet_next;
    for (int i = 0; i < packet_size; ++i)
      if (packet_s[static_cast<size_t>(i)] == s) {
        packet_next = i;
        return i;
      }
    return -1;
  }

  /// exact_hit for a ray of the packet (lane i), after the clip said it is inside.
  double packet_hit(int i, const RootGuess& guess, double& band) {
    const size_t lane = static_cast<size_t>(i);
    band = packet_band[lane];
    // A vanishing leading coefficient lowers the degree: the general entry trims it.
    if (!((packet_full_bits >> i) & 1))
      return finder.find_first_root(
          std::span<const double>(lane_coeffs(i), static_cast<size_t>(degree + 1)),
          packet_t0[lane], packet_t1[lane], band, guess);
    return finder.find_first_root_on_unit(
        std::span<const double>(packet_g[lane], static_cast<size_t>(degree + 1)),
        packet_t0[lane], packet_t1[lane], band, guess);
  }

  double value_on_ray(const Vec3& dir, double t) { return evaluator.value(eye + t * dir); }

  std::optional<double> interval_hit(const Vec3& dir, double t0, double t1) {
    const double leaf = std::max(options.interval_tolerance, 1e-15) * (t1 - t0);
    const double tol = 1e-13 * (t1 - t0);
    auto f = [&](double t) { return value_on_ray(dir, t); };
    segments.clear();
    segments.push_back({t0, t1});
    while (!segments.empty()) {
      const Segment s = segments.back();
      segments.pop_back();
      detail::Interval box[3];
      for (int k = 0; k < 3; ++k) {
        const double u = eye[k] + s.a * dir[k], v = eye[k] + s.b * dir[k];
        box[k] = {std::min(u, v), std::max(u, v)};
      }
      detail::Interval e[4];  // F, Fx, Fy, Fz over the segment's box
      intervals->eval_gradient(box[0], box[1], box[2], e);
      if (e[0].is_empty() || !e[0].contains_zero()) continue;
      // F along the ray has derivative ∇F·dir: when its enclosure excludes 0, F is monotone on
      // the segment, so the end values decide (one root or none) without subdividing.
      detail::Interval slope{0, 0};
      for (int k = 0; k < 3; ++k) {
        const double lo = e[k + 1].lo * dir[k], hi = e[k + 1].hi * dir[k];
        slope.lo += std::min(lo, hi);
        slope.hi += std::max(lo, hi);
      }
      const bool finite_slope = std::isfinite(slope.lo) && std::isfinite(slope.hi);
      const bool monotone = finite_slope && !slope.contains_zero();
      if (finite_slope && !monotone) {
        // Mean value form, tighter than the direct enclosure on short segments:
        // F(t) ∈ F(m) + slope · [a − m, b − m].
        const double m = 0.5 * (s.a + s.b), fm = f(m), h = 0.5 * (s.b - s.a);
        const double reach = std::max(std::abs(slope.lo), std::abs(slope.hi)) * h;
        if (std::isfinite(fm) && std::abs(fm) > reach * (1 + 1e-12)) continue;
      }
      if (monotone || s.b - s.a <= leaf) {
        const double fa = f(s.a), fb = f(s.b);
        if (fa == 0) return s.a;
        if (std::isfinite(fa) && std::isfinite(fb) && (fa > 0) != (fb > 0))
          return refine_sign_change(f, s.a, s.b, fa, fb, tol);
        continue;
      }
      const double m = 0.5 * (s.a + s.b);
      segments.push_back({m, s.b});
      segments.push_back({s.a, m});
    }
    return std::nullopt;
  }

  /// The first hit of the row's ray at s (NaN: none), and the side of the surface the ray
  /// starts on (+1, −1, 0 when F vanishes there).
  double cast(double s, const RootGuess& guess, int& side) {
    constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
    cast_lane = packet_ready ? packet_lane(s) : -1;
    if (const int lane = cast_lane; lane >= 0) {
      if (!packet_open[static_cast<size_t>(lane)]) return kNone;
      double band = 0;
      const double t = packet_hit(lane, guess, band);
      const double v = finder.start_value();
      side = std::abs(v) <= band ? 0 : (v > 0 ? 1 : -1);
      return t;
    }
    double t0 = 0, t1 = 0;
    if (!clip(s, t0, t1)) return kNone;
    if (exact) {
      double band = 0;
      const double t = exact_hit(s, t0, t1, guess, band);
      // F keeps its sign on [t0, hit) since the hit is the first root.
      const double v = finder.start_value();
      side = std::abs(v) <= band ? 0 : (v > 0 ? 1 : -1);
      return t;
    }
    const Vec3 dir = direction(s);
    const std::optional<double> t = interval_hit(dir, t0, t1);
    if (!t) return kNone;
    const double v = value_on_ray(dir, t0);
    side = v > 0 ? 1 : (v < 0 ? -1 : 0);
    return *t;
  }

  /// A bound on the magnitude of the terms of ∇F at p: Σ_k gradient_bound[k] max|p_i|^k.
  double gradient_scale(const Vec3& p) const {
    const double m = p.cwiseAbs().maxCoeff();
    double bound = 0;
    for (size_t k = gradient_bound.size(); k-- > 0;) bound = std::fma(bound, m, gradient_bound[k]);
    return bound;
  }

  /// ∇F at p from F's own terms (well conditioned near the surface, unlike the translated
  /// form).
  void gradient(const Vec3& p, Vec3& g) {
    double* mono = powers.data();
    derivative_monomials.evaluate(p, mono);
    sparse_gradient(derivative, mono, g.data());
  }

  bool intersect_in_row(double s, SurfaceHit& hit, const RootGuess& guess) {
    int side = 0;
    const double t = cast(s, guess, side);
    if (std::isnan(t)) return false;
    if (cast_lane >= 0) ray_coeffs = lane_coeffs(cast_lane);
    complete(s, t, side, hit);
    return true;
  }

  /// The row's ray at s hits at t (side as from cast; the ray's polynomial at ray_coeffs):
  /// its point, normal and side. Fused multiply-adds where complete4 uses them.
  void complete(double s, double t, int side, SurfaceHit& hit) {
    const double dx = std::fma(s, step.x(), base.x()), dy = std::fma(s, step.y(), base.y()),
                 dz = std::fma(s, step.z(), base.z());
    const Vec3 dir(dx, dy, dz);
    hit.t = t;
    hit.point = Vec3(std::fma(t, dx, eye.x()), std::fma(t, dy, eye.y()), std::fma(t, dz, eye.z()));
    Vec3 g;
    if (exact) {
      // ∇F lost to cancellation (a node, or a squared surface where ∇F = 2g∇g is tiny at the
      // root) has a meaningless direction: treat it as vanishing.
      const double floor = kRelativeGradientFloor * gradient_scale(hit.point);
      // The row's expansions give ∇F cheaply; it is used where it is far from vanishing and
      // far above the bound on its own rounding (a relative error below 1e-3 in that worst
      // case, below 1e-9 in practice) and the decision below is the same. Elsewhere
      // (near nodes, on squared surfaces, for single rays) ∇F comes from F's own terms.
      double error = 0;
      if (row_gradient(s, t, g, error) &&
          in_open_range(squared_norm(g.x(), g.y(), g.z()),
                        std::max(square(kRowGradientMargin * floor),
                                 square(kRowGradientAccuracy * error)))) {
        hit.singular = false;
      } else {
        gradient(hit.point, g);
        hit.singular = !(g.allFinite() && g.squaredNorm() > floor * floor);
      }
    } else {
      evaluator.value_gradient(hit.point, g);
      hit.singular = !(g.allFinite() && g.squaredNorm() > 0);
    }
    if (hit.singular) g = fallback_normal(hit.point, dir);
    // Which side the eye is on: the sign F has along the ray before the hit, or, for a hit
    // at the clip entry, the gradient's direction.
    const double gd = std::fma(g.z(), dz, std::fma(g.y(), dy, g.x() * dx));
    hit.front = side != 0 ? side > 0 : gd < 0;
    const double k = (gd > 0 ? -1 : 1) / std::sqrt(squared_norm(g.x(), g.y(), g.z()));
    hit.normal = Vec3(k * g.x(), k * g.y(), k * g.z());
  }

  /// Where ∇F = 0 (a node, or every point of a squared surface such as (x²+y²+z²−1)²): the
  /// Hessian's principal eigenvector is the normal of the underlying smooth sheet when F is
  /// a square; otherwise face the viewer.
  Vec3 fallback_normal(const Vec3& p, const Vec3& dir) {
    const FieldSample s = evaluator.sample(p, true, false);
    if (s.hessian.allFinite() && s.hessian.norm() > 0) {
      Eigen::SelfAdjointEigenSolver<Mat3> eig(s.hessian);
      const Eigen::Vector3d ev = eig.eigenvalues().cwiseAbs();
      int best = 0;
      ev.maxCoeff(&best);
      const double second = (ev.sum() - ev[best]);
      // Only a clearly dominant direction is a sheet's normal (rank one, as for F = g²).
      if (ev[best] > 4 * second) return eig.eigenvectors().col(best);
    }
    return -dir;
  }
};

SurfaceRayCaster::SurfaceRayCaster(const Surface& surface, const Vec3& eye,
                                   const RaycastOptions& options)
    : impl_(std::make_unique<Impl>(surface, eye, options)) {}
SurfaceRayCaster::~SurfaceRayCaster() = default;
SurfaceRayCaster::SurfaceRayCaster(SurfaceRayCaster&&) noexcept = default;
SurfaceRayCaster& SurfaceRayCaster::operator=(SurfaceRayCaster&&) noexcept = default;

bool SurfaceRayCaster::is_exact() const { return impl_->exact; }
std::optional<double> SurfaceRayCaster::first_hit(const Vec3& dir) {
  impl_->begin_row(dir, Vec3::Zero());
  int side = 0;
  const double t = impl_->cast(0.0, {}, side);
  return std::isnan(t) ? std::nullopt : std::optional<double>(t);
}
bool SurfaceRayCaster::intersect(const Vec3& dir, SurfaceHit& hit) {
  impl_->begin_row(dir, Vec3::Zero());
  return impl_->intersect_in_row(0.0, hit, {});
}
void SurfaceRayCaster::begin_row(const Vec3& base, const Vec3& step) {
  impl_->begin_row(base, step);
}
void SurfaceRayCaster::row_extent(double& s_min, double& s_max) const {
  s_min = impl_->s_min;
  s_max = impl_->s_max;
}
int SurfaceRayCaster::prepare_in_row(std::span<const double> s) { return impl_->prepare(s); }
bool SurfaceRayCaster::first_hit_in_row(double s, const RootGuess& guess, double& t) {
  t = impl_->first_hit_in_row(s, guess);
  return !std::isnan(t);
}
int SurfaceRayCaster::packet_hits(SurfaceHit (&hits)[4]) { return impl_->packet_hits(hits); }
bool SurfaceRayCaster::intersect_in_row(double s, SurfaceHit& hit, const RootGuess& guess) {
  return impl_->intersect_in_row(s, hit, guess);
}
const RootStats& SurfaceRayCaster::root_stats() const { return impl_->finder.stats(); }

}  // namespace zeroset
