#include "zeroset/render/raycast.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "interval_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/polynomial.h"

namespace zeroset {
namespace {

constexpr int kN = RootFinder::kMaxDegree + 1;
// |∇F| below this fraction of the magnitude of its terms counts as ∇F = 0 (see intersect).
constexpr double kRelativeGradientFloor = 1e-6;

/// Number of monomials in x, y, z of degree ≤ D.
constexpr int monomial_count(int D) { return (D + 1) * (D + 2) * (D + 3) / 6; }

/// The same enumeration as MonomialTable for a degree known at compile time, so that a
/// direction's monomials and the coefficients of f are computed in fully unrolled code.
template <int D>
struct FixedMonomials {
  static constexpr int kCount = monomial_count(D);
  std::array<int, kCount> parent{};
  std::array<int, kCount> axis{};
  std::array<int, D + 1> degree_end{};
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
      degree_end[static_cast<size_t>(total)] = pos;
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

/// coeffs[k] = Σ over the monomials of degree k of c · d^monomial, unrolled for degree D.
template <int D>
void restrict_fixed(const double* c, const double* d, double* coeffs) {
  static constexpr FixedMonomials<D> t{};
  double mono[FixedMonomials<D>::kCount];
  monomials_fixed<D>(d, mono);
  [&]<size_t... K>(std::index_sequence<K...>) {
    ((coeffs[K] = [&] {
       double sum = 0;
       for (int m = K == 0 ? 0 : t.degree_end[K - 1]; m < t.degree_end[K]; ++m)
         sum += c[m] * mono[m];
       return sum;
     }()),
     ...);
  }(std::make_index_sequence<D + 1>{});
}

/// A sparse partial derivative: (monomial position, coefficient) of its nonzero terms.
using SparseTerms = std::vector<std::pair<int, double>>;

/// g[a] = Σ c · mono[position] over the terms of partial derivative a.
inline void sparse_gradient(const std::array<SparseTerms, 3>& terms, const double* mono,
                            double* g) {
  for (int a = 0; a < 3; ++a) {
    double sum = 0;
    for (const auto& [m, c] : terms[static_cast<size_t>(a)]) sum += c * mono[m];
    g[a] = sum;
  }
}

/// Every monomial x^i y^j z^k of degree ≤ D in graded order (degree, then descending i, j),
/// each one the product of an earlier one (`parent`) and one variable (`axis`): the monomials
/// of a direction are then one multiplication each.
struct MonomialTable {
  std::vector<int> parent;
  std::vector<int> axis;
  std::vector<size_t> degree_end;  // monomials of degree k end at degree_end[k]
  std::vector<int> index;          // (i, j, k) → position, at (i·(D+1) + j)·(D+1) + k
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
      degree_end.push_back(parent.size());
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
  std::array<SparseTerms, 3> derivative;  // positions in derivative_monomials
  std::vector<double> gradient_bound;  // [k]: Σ |coefficient| over degree k of all three
  MonomialTable monomials{0};
  std::vector<double> translated;  // G(p) = F(eye + p): coefficient of each monomial
  std::vector<double> powers;      // scratch: monomials of a direction or of a hit point
  RootFinder finder;
  std::array<double, kN> coeffs{};
  // bounds[k]·max|d_i|^k ≥ |G_k(d)| for every direction d, and ≥ the rounding error scale
  // of G_k: the sum of the coefficients of degree k of |F| translated by |eye|.
  std::array<double, kN> bounds{};
  double last_band = 0;
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
    exact = !o.force_interval && field.is_polynomial() &&
            field.degree() <= RootFinder::kMaxDegree;
    if (exact) {
      const Polynomial poly = field.polynomial();
      degree = std::max(poly.degree(), 0);
      const Polynomial g = poly.translated(eye);
      derivative_monomials = MonomialTable(std::max(degree - 1, 0));
      gradient_bound.assign(static_cast<size_t>(derivative_monomials.D + 1), 0.0);
      // Polynomial's terms are unique, so each derivative gets each monomial at most once.
      auto add_derivative = [&](int axis, int i, int j, int k, double c) {
        derivative[static_cast<size_t>(axis)].emplace_back(derivative_monomials.at(i, j, k), c);
        gradient_bound[static_cast<size_t>(i + j + k)] += std::abs(c);
      };
      std::vector<Monomial> abs_terms;
      for (const Monomial& m : poly.terms()) {
        abs_terms.push_back({m.i, m.j, m.k, std::abs(m.c)});
        if (m.i > 0) add_derivative(0, m.i - 1, m.j, m.k, m.i * m.c);
        if (m.j > 0) add_derivative(1, m.i, m.j - 1, m.k, m.j * m.c);
        if (m.k > 0) add_derivative(2, m.i, m.j, m.k - 1, m.k * m.c);
      }
      const Polynomial gb = Polynomial(abs_terms).translated(eye.cwiseAbs());
      monomials = MonomialTable(degree);
      translated.assign(monomials.size(), 0.0);
      powers.assign(monomials.size(), 0.0);
      for (const Monomial& m : g.terms())
        translated[static_cast<size_t>(monomials.at(m.i, m.j, m.k))] = m.c;
      for (const Monomial& m : gb.terms()) bounds[static_cast<size_t>(m.degree())] += m.c;
    } else {
      intervals = std::make_unique<detail::IntervalEvaluator>(field);
    }
  }

  bool clip(const Vec3& dir, double& t0, double& t1) const {
    return surface.clip.ray_interval(eye, dir, 0.0, t0, t1);
  }

  /// f(t) = G(t·dir) coefficients: f_k = Σ over monomials of degree k of c · dir^monomial.
  void restrict(const Vec3& dir) {
    const double d[3] = {dir.x(), dir.y(), dir.z()};
    switch (degree) {
      case 2: return restrict_fixed<2>(translated.data(), d, coeffs.data());
      case 3: return restrict_fixed<3>(translated.data(), d, coeffs.data());
      case 4: return restrict_fixed<4>(translated.data(), d, coeffs.data());
      case 5: return restrict_fixed<5>(translated.data(), d, coeffs.data());
      case 6: return restrict_fixed<6>(translated.data(), d, coeffs.data());
      default: break;
    }
    double* mono = powers.data();
    monomials.evaluate(dir, mono);
    const double* c = translated.data();
    size_t m = 0;
    for (int k = 0; k <= degree; ++k) {
      // Two chains per degree, summed in registers.
      const size_t end = monomials.degree_end[static_cast<size_t>(k)];
      double c0 = 0, c1 = 0;
      for (; m + 1 < end; m += 2) {
        c0 += c[m] * mono[m];
        c1 += c[m + 1] * mono[m + 1];
      }
      if (m < end) {
        c0 += c[m] * mono[m];
        ++m;
      }
      coeffs[static_cast<size_t>(k)] = c0 + c1;
    }
  }

  std::optional<double> exact_hit(const Vec3& dir, double t0, double t1) {
    restrict(dir);
    const std::span<const double> c(coeffs.data(), static_cast<size_t>(degree + 1));
    // A monomial of degree k in the direction's components is at most max|d_i|^k.
    const double m = dir.cwiseAbs().maxCoeff();
    last_band = rounding_band(std::span<const double>(bounds.data(), c.size()), t1 * m);
    return finder.first_root(c, t0, t1, last_band);
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

  std::optional<double> first_hit(const Vec3& dir) {
    double t0 = 0, t1 = 0;
    if (!clip(dir, t0, t1)) return std::nullopt;
    return exact ? exact_hit(dir, t0, t1) : interval_hit(dir, t0, t1);
  }

  /// ∇F at p from F's own terms (well conditioned near the surface, unlike the translated
  /// form). Returns a bound on the magnitude of its terms: Σ_k gradient_bound[k] max|p_i|^k.
  double gradient(const Vec3& p, Vec3& g) {
    double* mono = powers.data();
    derivative_monomials.evaluate(p, mono);
    sparse_gradient(derivative, mono, g.data());
    return evaluate_polynomial(gradient_bound, p.cwiseAbs().maxCoeff());
  }

  /// Sign of F just before the hit (constant on [t0, hit) since the hit is the first root);
  /// 0 when F vanishes at the entry point too.
  int sign_before(const Vec3& dir, double t0) {
    if (exact) {
      const double v =
          evaluate_polynomial(std::span<const double>(coeffs.data(), degree + 1), t0);
      return std::abs(v) <= last_band ? 0 : (v > 0 ? 1 : -1);
    }
    const double v = value_on_ray(dir, t0);
    return v > 0 ? 1 : (v < 0 ? -1 : 0);
  }

  bool intersect(const Vec3& dir, SurfaceHit& hit) {
    double t0 = 0, t1 = 0;
    if (!clip(dir, t0, t1)) return false;
    const std::optional<double> t = exact ? exact_hit(dir, t0, t1) : interval_hit(dir, t0, t1);
    if (!t) return false;
    hit.t = *t;
    hit.point = eye + *t * dir;
    Vec3 g;
    if (exact) {
      // ∇F lost to cancellation (a node, or a squared surface where ∇F = 2g∇g is tiny at the
      // root) has a meaningless direction: treat it as vanishing.
      const double scale = gradient(hit.point, g);
      hit.singular = !(g.allFinite() && g.norm() > kRelativeGradientFloor * scale);
    } else {
      evaluator.value_gradient(hit.point, g);
      hit.singular = !(g.allFinite() && g.squaredNorm() > 0);
    }
    if (hit.singular) g = fallback_normal(hit.point, dir);
    // Which side the eye is on: the sign F has along the ray before the hit, or, for a hit
    // at the clip entry, the gradient's direction.
    const int side = sign_before(dir, t0);
    hit.front = side != 0 ? side > 0 : g.dot(dir) < 0;
    hit.normal = g.normalized();
    if (hit.normal.dot(dir) > 0) hit.normal = -hit.normal;
    return true;
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
  return impl_->first_hit(dir);
}
bool SurfaceRayCaster::intersect(const Vec3& dir, SurfaceHit& hit) {
  return impl_->intersect(dir, hit);
}
const RootStats& SurfaceRayCaster::root_stats() const { return impl_->finder.stats(); }

}  // namespace zeroset
