// The accurate path of exact ray casting: F restricted to one ray in double-double, written on
// the ray's clipped segment, for the hits the fast path cannot place (see docs/rendering.md,
// "Accuracy"). The fast path (raycast_rows.cpp) restricts G, F translated to the eye, along a
// whole row in double: at degree 8 to 12 with the eye a few clip radii away, its rounding band
// is wide enough to hold spurious roots (tangencies the surface does not have) and to blur
// roots next to nodes. Here G's coefficients are computed in double-double once per eye, each
// uncertain ray is restricted exactly enough that only the final rounding to double counts,
// and the polynomial is shifted to its segment before it is rounded, so its band is that of
// F's values on the segment rather than of the translation.
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "double_double_detail.h"
#include "raycast_detail.h"

namespace zeroset::detail {
namespace {

/// G = F(eye + p) in double-double: for each term c·x^i y^j z^k of F, the binomial expansion
/// of c·(e_x + p_x)^i (e_y + p_y)^j (e_z + p_z)^k, with the magnitudes of the products summed
/// alongside for the error bound.
void translate_accurately(RayCaster& rc) {
  const int n = rc.degree + 1;
  std::vector<double> binomial(static_cast<size_t>(n * n), 0.0);
  for (int i = 0; i < n; ++i) {
    binomial[static_cast<size_t>(i * n)] = 1;
    for (int a = 1; a <= i; ++a)
      binomial[static_cast<size_t>(i * n + a)] =
          binomial[static_cast<size_t>((i - 1) * n + a - 1)] +
          (a < i ? binomial[static_cast<size_t>((i - 1) * n + a)] : 0.0);
  }
  // powers[axis][m] = e_axis^m, and their magnitudes.
  std::vector<DoubleDouble> powers(static_cast<size_t>(3 * n));
  for (int axis = 0; axis < 3; ++axis) {
    powers[static_cast<size_t>(axis * n)] = {1, 0};
    for (int m = 1; m < n; ++m)
      powers[static_cast<size_t>(axis * n + m)] =
          powers[static_cast<size_t>(axis * n + m - 1)] * rc.eye[axis];
  }
  const MonomialTable& table = rc.row_monomials;
  std::vector<DoubleDouble> sum(table.size());
  std::vector<double> magnitude(table.size(), 0.0);
  std::vector<DoubleDouble> px, py;
  for (const Monomial& term : rc.polynomial.terms()) {
    auto factor = [&](int axis, int e, int a) {
      return powers[static_cast<size_t>(axis * n + e - a)] *
             binomial[static_cast<size_t>(e * n + a)];
    };
    px.clear();
    py.clear();
    for (int a = 0; a <= term.i; ++a) px.push_back(factor(0, term.i, a) * term.c);
    for (int b = 0; b <= term.j; ++b) py.push_back(factor(1, term.j, b));
    for (int c = 0; c <= term.k; ++c) {
      const DoubleDouble z = factor(2, term.k, c);
      for (int b = 0; b <= term.j; ++b) {
        const DoubleDouble yz = py[static_cast<size_t>(b)] * z;
        for (int a = 0; a <= term.i; ++a) {
          const DoubleDouble v = px[static_cast<size_t>(a)] * yz;
          const size_t m = static_cast<size_t>(table.at(a, b, c));
          sum[m] = sum[m] + v;
          magnitude[m] += std::abs(v.hi);
        }
      }
    }
  }
  rc.accurate_terms.clear();
  for (size_t m = 0; m < sum.size(); ++m)
    if (magnitude[m] != 0)
      rc.accurate_terms.push_back({static_cast<int>(m), rc.degree_of[m], sum[m], magnitude[m]});
  rc.accurate_mono.resize(rc.mono_poly.size());
  rc.accurate_abs.resize(rc.mono_poly.size());
  rc.accurate_ready = true;
}

/// f[k], k ≤ degree: G(q + t·dir) = Σ_k f[k] t^k in double-double (q = 0 for rays from the
/// eye), and magnitude[k] ≥ the sum of the magnitudes of the products added into f[k].
void restrict_accurately(RayCaster& rc, const Vec3& q, const Vec3& dir, DoubleDouble* f,
                         double* magnitude) {
  const int* parent = rc.row_monomials.parent.data();
  const int* axis = rc.row_monomials.axis.data();
  const int* offset = rc.mono_offset.data();
  DoubleDouble* mono = rc.accurate_mono.data();
  double* mono_abs = rc.accurate_abs.data();
  std::fill_n(f, rc.degree + 1, DoubleDouble{});
  std::fill_n(magnitude, rc.degree + 1, 0.0);
  const int count = static_cast<int>(rc.row_monomials.size());
  if (q.isZero()) {
    // G_k(dir) t^k: each monomial of dir is one number.
    mono[0] = {1, 0};
    mono_abs[0] = 1;
    for (int m = 1; m < count; ++m) {
      mono[m] = mono[parent[m]] * dir[axis[m]];
      mono_abs[m] = mono_abs[parent[m]] * std::abs(dir[axis[m]]);
    }
    for (const AccurateTerm& t : rc.accurate_terms) {
      f[t.degree] = f[t.degree] + t.c * mono[t.position];
      magnitude[t.degree] += t.magnitude * mono_abs[t.position];
    }
    return;
  }
  // Each monomial of q + t·dir is a polynomial in t of its degree: its parent's times
  // (q_a + t·dir_a), laid out as the row's monomials (mono_offset).
  mono[0] = {1, 0};
  mono_abs[0] = 1;
  for (int m = 1, k = 1, next = 4; m < count; ++m) {
    if (m == next) {
      ++k;
      next += (k + 1) * (k + 2) / 2;
    }
    const DoubleDouble* p = mono + offset[parent[m]];
    const double* pa = mono_abs + offset[parent[m]];
    DoubleDouble* r = mono + offset[m];
    double* ra = mono_abs + offset[m];
    const double qa = q[axis[m]], da = dir[axis[m]];
    r[0] = p[0] * qa;
    ra[0] = pa[0] * std::abs(qa);
    for (int j = 1; j < k; ++j) {
      r[j] = p[j] * qa + p[j - 1] * da;
      ra[j] = pa[j] * std::abs(qa) + pa[j - 1] * std::abs(da);
    }
    r[k] = p[k - 1] * da;
    ra[k] = pa[k - 1] * std::abs(da);
  }
  for (const AccurateTerm& t : rc.accurate_terms) {
    const DoubleDouble* p = mono + offset[t.position];
    const double* pa = mono_abs + offset[t.position];
    for (int j = 0; j <= t.degree; ++j) {
      f[j] = f[j] + t.c * p[j];
      magnitude[j] += t.magnitude * pa[j];
    }
  }
}

/// Whether the root of Σ_k c[k] x^k near x (|c| ≤ band there counts as zero) is placed within
/// `reach` of x: by the slope for a simple root, else by the first derivative that does not
/// vanish, the distance at which its Taylor term alone exceeds the band (a double root of a
/// squared surface, a tangent ray).
bool root_is_placed(const double* c, int d, double x, double band, double reach) {
  double slope = 0;
  for (int k = d; k >= 1; --k) slope = std::fma(slope, x, k * c[k]);
  if (band <= reach * std::abs(slope)) return true;
  // The Taylor coefficients at x, c(x + h) = Σ_k a_k h^k, by repeated synthetic division.
  std::array<double, kN> a{};
  std::copy_n(c, d + 1, a.begin());
  for (int i = 0; i < d; ++i)
    for (int k = d - 1; k >= i; --k)
      a[static_cast<size_t>(k)] =
          std::fma(a[static_cast<size_t>(k + 1)], x, a[static_cast<size_t>(k)]);
  for (int k = 2; k <= d; ++k) {
    const double ak = std::abs(a[static_cast<size_t>(k)]);
    if (ak > 0) return std::pow(band / ak, 1.0 / k) <= reach;
  }
  return false;
}

}  // namespace

bool hit_is_certain(const RayCaster& rc, const double* f, double t, double band, double dir_norm) {
  // The root lies within the returned reach of t (in t), the ray's length unit being |dir|.
  return root_is_placed(f, rc.degree, t, band, kCertainHit * rc.scene_radius / dir_norm);
}

double accurate_hit(RayCaster& rc, double s, double t0, double t1, const RootGuess& guess,
                    double& band, double& start) {
  if (!rc.accurate_ready) translate_accurately(rc);
  ++rc.accurate_rays;
  const Vec3 q = rc.parallel ? Vec3(s * rc.step) : Vec3::Zero();
  const Vec3 dir = direction(rc, s);
  const double dir_norm = dir.norm();
  std::array<DoubleDouble, kN> f;
  std::array<double, kN> magnitude{};
  restrict_accurately(rc, q, dir, f.data(), magnitude.data());
  const int d = rc.degree;
  // The error of the double-double arithmetic, on the scale of the products' sizes.
  double error = 0;
  for (int k = d; k >= 0; --k) error = error * t1 + magnitude[static_cast<size_t>(k)];
  error *= 8.0 * (d + 1) * (d + 1) * kDoubleDoubleEpsilon;
  // g(u) = f(a + u·(b − a)) on a piece [a, b] of the segment, made in double-double and then
  // rounded, is accurate to its rounding band; but in the power basis on a wide piece of a
  // degree-12 ray that band can exceed the values of F by orders of magnitude. So the search
  // runs on pieces, depth first from the left, and a piece whose first root the band does not
  // place (a root through the band, or one band / |g'| wide) is halved, down to kAccurateDepth
  // halvings.
  std::array<double, kN> g{};
  auto unit_form = [&](double a, double b) {
    std::array<DoubleDouble, kN> h = f;
    for (int i = 0; i < d; ++i)
      for (int k = d - 1; k >= i; --k)
        h[static_cast<size_t>(k)] = h[static_cast<size_t>(k)] + h[static_cast<size_t>(k + 1)] * a;
    DoubleDouble scale{1, 0};
    for (int k = 0; k <= d; ++k) {
      g[static_cast<size_t>(k)] = to_double(h[static_cast<size_t>(k)] * scale);
      scale = scale * (b - a);
    }
    return rounding_band(std::span<const double>(g.data(), static_cast<size_t>(d + 1)), 1.0) +
           error;
  };
  struct Piece {
    double a, b;
    int depth;
  };
  std::array<Piece, 2 * kAccurateDepth + 2> stack;
  int size = 0;
  stack[static_cast<size_t>(size++)] = {t0, t1, 0};
  start = std::numeric_limits<double>::quiet_NaN();
  while (size > 0) {
    const Piece p = stack[static_cast<size_t>(--size)];
    const double w = p.b - p.a;
    band = unit_form(p.a, p.b);
    if (std::isnan(start)) start = g[0];
    RootGuess unit_guess;
    if (!std::isnan(guess.t) && w > 0) unit_guess = {(guess.t - p.a) / w, guess.spread / w};
    const double u = rc.finder.find_first_root(
        std::span<const double>(g.data(), static_cast<size_t>(d + 1)), 0.0, 1.0, band, unit_guess);
    if (std::isnan(u)) continue;  // the band is valid: no root on this piece
    const bool placed = w > 0 && root_is_placed(g.data(), d, u, band,
                                                kCertainHit * rc.scene_radius / (w * dir_norm));
    if (placed || p.depth == kAccurateDepth || !(w > 0)) return p.a + u * w;
    const double mid = p.a + 0.5 * w;
    stack[static_cast<size_t>(size++)] = {mid, p.b, p.depth + 1};
    stack[static_cast<size_t>(size++)] = {p.a, mid, p.depth + 1};
  }
  return std::numeric_limits<double>::quiet_NaN();
}

}  // namespace zeroset::detail
