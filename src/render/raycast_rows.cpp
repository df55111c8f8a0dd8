// A row of rays base + s·step: the clip and G (F translated to the eye) expanded along it,
// and the first root of one ray of it.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>
#include <utility>

#include "raycast_detail.h"

namespace zeroset::detail {
namespace {

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

/// coeffs[m] = Σ_{k ≥ m} row[k(k+1)/2 + k − m] s^(k−m) for m ≤ d: the polynomial in t of
/// G(s·step + t·base) on a parallel row's ray, each coefficient by Horner in s. Returns the
/// rounding band at x, as restrict_in_row.
double restrict_in_parallel_row(const double* row, const double* band_coeffs, int d, double s,
                                double x, double* coeffs) {
  for (int m = 0; m <= d; ++m) {
    double v = row[d * (d + 1) / 2 + d - m];
    for (int k = d - 1; k >= m; --k) v = std::fma(v, s, row[k * (k + 1) / 2 + k - m]);
    coeffs[m] = v;
  }
  double band = band_coeffs[d];
  for (int k = d - 1; k >= 0; --k) band = std::fma(band, x, band_coeffs[k]);
  return band;
}

/// [s_min, s_max] ⊇ the s whose rays meet every clip sphere: with the eye outside a
/// sphere, the discriminant of clip() is a quadratic A s² + 2B s + C that is nonnegative
/// on an interval when A < 0. Widened well beyond rounding; clip() decides inside it.
void find_row_extent(RayCaster& rc) {
  rc.s_min = -std::numeric_limits<double>::infinity();
  rc.s_max = std::numeric_limits<double>::infinity();
  for (const SphereRow& r : rc.sphere_rows) {
    if (!(r.c > 0)) continue;  // the eye is inside: every ray meets the sphere
    const double A = r.b1 * r.b1 - r.c * r.a2, B = r.b0 * r.b1 - r.c * r.a1;
    const double C = r.b0 * r.b0 - r.c * r.a0;
    if (!(A < 0)) continue;  // no bound from this sphere (a row of one ray, step = 0)
    const double disc = B * B - A * C;
    if (disc < -1e-12 * (B * B + std::abs(A * C))) {  // the row's plane misses the sphere
      rc.s_min = std::numeric_limits<double>::infinity();
      rc.s_max = -rc.s_min;
      return;
    }
    const double q = -(B + std::copysign(std::sqrt(std::max(disc, 0.0)), B));
    double lo = q / A, hi = q != 0 ? C / q : -B / A;
    if (lo > hi) std::swap(lo, hi);
    const double margin = 1e-7 * (1 + std::abs(lo) + std::abs(hi));
    rc.s_min = std::max(rc.s_min, lo - margin);
    rc.s_max = std::min(rc.s_max, hi + margin);
  }
}

/// row = G restricted to the row's directions: each term c·x^i y^j z^l of G becomes
/// c·(bx + s·sx)^i (by + s·sy)^j (bz + s·sz)^l, multiplied out in s. With step = 0 (a
/// single ray) only the constant terms are formed.
void expand_row(RayCaster& rc) {
  const int n = rc.degree + 1;
  const bool flat = rc.step.isZero();
  // Each monomial as a polynomial in s: its parent's times (base_a + s·step_a), so every
  // monomial costs deg + 1 multiply-adds, and each term of G or ∇G·n then deg + 1 more.
  const int* parent = rc.row_monomials.parent.data();
  const int* axis = rc.row_monomials.axis.data();
  const int* offset = rc.mono_offset.data();
  double* poly = rc.mono_poly.data();
  poly[0] = 1;
  // Graded order: the monomials of degree k start at k(k+1)(k+2)/6 (`next` for k + 1).
  for (int m = 1, k = 1, next = 4; m < static_cast<int>(rc.row_monomials.size()); ++m) {
    if (m == next) {
      ++k;
      next += (k + 1) * (k + 2) / 2;
    }
    const double* p = poly + offset[parent[m]];
    double* q = poly + offset[m];
    const double b = rc.base[axis[m]], st = rc.step[axis[m]];
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
  std::fill_n(rc.row.begin(), n * (n + 1) / 2, 0.0);
  for (const RowTerm& t : rc.row_terms) add_term(t.position, t.degree, t.c, rc.row.data());
  const bool packets = rc.degree <= kPacketDegree;
  if (packets) broadcast(rc.row.data(), n * (n + 1) / 2, rc.row4);
  rc.has_row_normals = !flat;
  if (!rc.has_row_normals) return;
  for (int k = 1; k <= rc.degree; ++k)
    for (int j = 0; j < k; ++j)
      rc.row_ds[static_cast<size_t>(k * (k - 1) / 2 + j)] =
          (j + 1) * rc.row[static_cast<size_t>(k * (k + 1) / 2 + j + 1)];
  rc.row_normal = rc.base.cross(rc.step);
  rc.row_dot = rc.base.dot(rc.step);
  rc.row_ss = rc.step.squaredNorm();
  rc.row_inverse_nn = 1 / rc.row_normal.squaredNorm();
  std::fill_n(rc.normal_row.begin(), rc.degree * (rc.degree + 1) / 2, 0.0);
  for (const PartialsTerm& t : rc.translated_gradient)
    add_term(t.position, t.degree, t.c.dot(rc.row_normal), rc.normal_row.data());
  if (packets) {
    broadcast(rc.row_ds.data(), rc.degree * (rc.degree + 1) / 2, rc.row_ds4);
    broadcast(rc.normal_row.data(), rc.degree * (rc.degree + 1) / 2, rc.normal_row4);
  }
}

/// max_i |base_i + s·step_i|, with fused multiply-adds as in prepare4.
double max_abs_direction(const RayCaster& rc, double s) {
  return std::max({std::abs(std::fma(s, rc.step.x(), rc.base.x())),
                   std::abs(std::fma(s, rc.step.y(), rc.base.y())),
                   std::abs(std::fma(s, rc.step.z(), rc.base.z()))});
}

}  // namespace

void begin_row(RayCaster& rc, const Vec3& row_base, const Vec3& row_step) {
  rc.parallel = false;
  rc.packet_size = 0;
  rc.packet_ready = false;
  rc.packet_hit_bits = rc.packet_done_bits = 0;
  rc.base = row_base;
  rc.step = row_step;
  for (size_t i = 0; i < rc.sphere_rows.size(); ++i) {
    const SphereClip& sphere = rc.surface.clip.spheres[i];
    const Vec3 oc = rc.eye - sphere.center;
    rc.sphere_rows[i] = {rc.base.squaredNorm(), rc.base.dot(rc.step),
                         rc.step.squaredNorm(), oc.dot(rc.base),
                         oc.dot(rc.step),       oc.squaredNorm() - sphere.radius * sphere.radius};
  }
  for (size_t i = 0; i < rc.plane_rows.size(); ++i) {
    const HalfSpaceClip& plane = rc.surface.clip.planes[i];
    rc.plane_rows[i] = {plane.normal.dot(rc.base), plane.normal.dot(rc.step),
                        plane.normal.dot(rc.eye) - plane.offset};
  }
  find_row_extent(rc);
  if (rc.exact) expand_row(rc);
}

void begin_parallel_row(RayCaster& rc, const Vec3& origin, const Vec3& origin_step,
                        const Vec3& dir) {
  if (rc.exact)
    set_eye(rc, origin);
  else
    rc.eye = origin;
  // G along the row's plane, as for the perspective row with directions dir + s·origin_step
  // (see RayCaster::row); the clip and the normals are the parallel rays' own.
  begin_row(rc, dir, origin_step);
  rc.parallel = true;
  rc.has_row_normals = false;
  rc.s_min = -std::numeric_limits<double>::infinity();
  rc.s_max = std::numeric_limits<double>::infinity();
}

bool clip(const RayCaster& rc, double s, double& t0, double& t1) {
  t0 = 0;
  t1 = std::numeric_limits<double>::infinity();
  if (rc.parallel) return rc.surface.clip.ray_interval(ray_origin(rc, s), rc.base, 0.0, t0, t1);
  // Fused multiply-adds in the order prepare4 uses, so that both give the same bits.
  for (const SphereRow& r : rc.sphere_rows) {
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
  for (const PlaneRow& r : rc.plane_rows) {
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

double exact_hit(RayCaster& rc, double s, double t0, double t1, const RootGuess& guess,
                 double& band) {
  // A monomial of degree k in the direction's components is at most max|d_i|^k. The
  // expansion in s rounds relative to (|base_i| + |s||step_i|)^k instead, but its error
  // stays far below the band (under 2% for the catalog's scenes across whole pictures).
  const double* r = rc.row.data();
  const double* b = rc.band_coeffs.data();
  double* c = rc.coeffs.data();
  rc.ray_coeffs = c;
  if (rc.parallel) {
    // The point s·step + t·base of the translated G: each coordinate at most
    // |s||step_i| + t1|base_i|.
    const double x = (std::abs(s) * rc.step.cwiseAbs() + t1 * rc.base.cwiseAbs()).maxCoeff();
    band = restrict_in_parallel_row(r, b, rc.degree, s, x, c);
    return rc.finder.find_first_root(std::span<const double>(c, static_cast<size_t>(rc.degree + 1)),
                                     t0, t1, band, guess);
  }
  // Above the packets' degrees the row's rounding is no longer far below the band: the band
  // is taken on the scale the expansion in s rounds on, max_i (|base_i| + |s||step_i|).
  const double x = t1 * (rc.degree <= kPacketDegree
                             ? max_abs_direction(rc, s)
                             : (rc.base.cwiseAbs() + std::abs(s) * rc.step.cwiseAbs()).maxCoeff());
  switch (rc.degree) {
    case 1:
      band = restrict_in_row<1>(r, b, rc.degree, s, x, c);
      break;
    case 2:
      band = restrict_in_row<2>(r, b, rc.degree, s, x, c);
      break;
    case 3:
      band = restrict_in_row<3>(r, b, rc.degree, s, x, c);
      break;
    case 4:
      band = restrict_in_row<4>(r, b, rc.degree, s, x, c);
      break;
    case 5:
      band = restrict_in_row<5>(r, b, rc.degree, s, x, c);
      break;
    case 6:
      band = restrict_in_row<6>(r, b, rc.degree, s, x, c);
      break;
    default:
      band = restrict_in_row<0>(r, b, rc.degree, s, x, c);
      break;
  }
  return rc.finder.find_first_root(std::span<const double>(c, static_cast<size_t>(rc.degree + 1)),
                                   t0, t1, band, guess);
}

}  // namespace zeroset::detail
