// Packets of four rays of a row (SurfaceRayCaster::prepare_in_row). With AVX2 their
// straight-line parts are done four at a time, bit for bit what the scalar code computes for
// each ray: the set-up (clip, restriction, rounding band, shift to the clipped interval) and
// the first levels of the isolation (hull_misses4) by prepare4, and the normals of their hits
// (packet_hits) by complete4. The rest of the isolation stays per ray.
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include "bernstein_detail.h"
#include "raycast_detail.h"

namespace zeroset::detail {
namespace {

#if defined(__AVX2__) && defined(__FMA__)
/// restrict_in_row and shift_to_unit for four rays at once, lane by lane the same operations
/// (so the same bits) as the scalar code: coeffs[k] and g[k] hold the four rays' k-th
/// coefficients. Lanes whose clip is empty compute garbage that is never used.
/// `row` and `band_coeffs` are restrict_in_row's, each coefficient in four lanes.
template <int D>
inline __m256d restrict_and_shift4(const double (*row)[4], const double (*band_coeffs)[4],
                                   __m256d s, __m256d x, __m256d t0, __m256d t1, __m256d* coeffs,
                                   __m256d* g) {
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
    return beyond | (left_rootless & rootless4<D, kLevels - 1>(right, band, lower, left_rootless));
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
    b[k] =
        _mm256_mul_pd(g[k], _mm256_set1_pd(detail::kInverseBinomials[D][static_cast<size_t>(k)]));
#pragma GCC unroll 16
  for (int i = 0; i < D; ++i)
#pragma GCC unroll 16
    for (int k = D; k > i; --k) b[k] = _mm256_add_pd(b[k], b[k - 1]);
  const __m256d lower = _mm256_sub_pd(_mm256_setzero_pd(), band);
  return rootless4<D, kHullLevels>(b, band, lower, lanes) & lanes;
}

/// out[i][k] = v[k][i]: four coefficients at a time by a 4×4 transpose, the rest by lane.
template <int D>
void store_lanes(const __m256d* v, double (*out)[kN]) {
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

/// Sets up the packet's four lanes; returns the lanes that miss.
template <int D>
int prepare4(RayCaster& rc, const double* sv) {
  const __m256d S = _mm256_loadu_pd(sv);
  const __m256d zero = _mm256_setzero_pd(), sign = _mm256_set1_pd(-0.0);
  __m256d t0 = zero, t1 = _mm256_set1_pd(std::numeric_limits<double>::infinity());
  __m256d miss = zero;  // all bits set in the lanes that miss
  for (const SphereRow& r : rc.sphere_rows) {
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
                                        _mm256_div_pd(c, qv), _mm256_cmp_pd(qv, zero, _CMP_NEQ_UQ));
    // As std::swap when r0 > r1 and std::max(t0, ·), std::min(t1, ·), NaNs included.
    t0 = _mm256_max_pd(_mm256_min_pd(r1, r0), t0);
    t1 = _mm256_min_pd(_mm256_max_pd(r0, r1), t1);
  }
  for (const PlaneRow& r : rc.plane_rows) {
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
  rc.packet_ready = true;
  if (inside_bits == 0) {
    rc.packet_open.fill(false);
    return 0xf;
  }
  const __m256d ax = _mm256_andnot_pd(
      sign, _mm256_fmadd_pd(S, _mm256_set1_pd(rc.step.x()), _mm256_set1_pd(rc.base.x())));
  const __m256d ay = _mm256_andnot_pd(
      sign, _mm256_fmadd_pd(S, _mm256_set1_pd(rc.step.y()), _mm256_set1_pd(rc.base.y())));
  const __m256d az = _mm256_andnot_pd(
      sign, _mm256_fmadd_pd(S, _mm256_set1_pd(rc.step.z()), _mm256_set1_pd(rc.base.z())));
  const __m256d x = _mm256_mul_pd(t1, _mm256_max_pd(_mm256_max_pd(ax, ay), az));
  __m256d c[D + 1], g[D + 1];
  const __m256d band = restrict_and_shift4<D>(rc.row4, rc.band4, S, x, t0, t1, c, g);
  _mm256_storeu_pd(rc.packet_t0.data(), t0);
  _mm256_storeu_pd(rc.packet_t1.data(), t1);
  _mm256_storeu_pd(rc.packet_band.data(), band);
  store_lanes<D>(g, rc.packet_g);
  for (int k = 0; k <= D; ++k) _mm256_store_pd(rc.packet_ck[k], c[k]);
  rc.packet_full_bits = _mm256_movemask_pd(_mm256_cmp_pd(c[D], _mm256_setzero_pd(), _CMP_NEQ_UQ));
  // Lanes of a lower degree are left to the general search, which trims the degree. The
  // scalar search splits the parts that hull_misses4 splits only when they are wider than
  // its tolerance: always, unless RootOptions::tolerance is raised to 2^(1 − kHullLevels).
  const bool same_splits = rc.options.roots.tolerance < 2.0 / (1 << kHullLevels);
  const int open = inside_bits &
                   ~(same_splits ? hull_misses4<D>(g, band, rc.packet_full_bits & inside_bits) : 0);
  for (int i = 0; i < 4; ++i) rc.packet_open[static_cast<size_t>(i)] = (open >> i) & 1;
  return ~open & 0xf;
}

/// complete for the lanes in `bits` where the row's gradient is used, four at once with
/// the same operations; returns the lanes done.
template <int D>
int complete4(const RayCaster& rc, int bits, SurfaceHit (&hits)[4]) {
  const __m256d sign = _mm256_set1_pd(-0.0), zero = _mm256_setzero_pd();
  const __m256d S = _mm256_loadu_pd(rc.packet_s.data()), T = _mm256_load_pd(rc.packet_t.data());
  const __m256d dx = _mm256_fmadd_pd(S, _mm256_set1_pd(rc.step.x()), _mm256_set1_pd(rc.base.x()));
  const __m256d dy = _mm256_fmadd_pd(S, _mm256_set1_pd(rc.step.y()), _mm256_set1_pd(rc.base.y()));
  const __m256d dz = _mm256_fmadd_pd(S, _mm256_set1_pd(rc.step.z()), _mm256_set1_pd(rc.base.z()));
  const __m256d px = _mm256_fmadd_pd(T, dx, _mm256_set1_pd(rc.eye.x()));
  const __m256d py = _mm256_fmadd_pd(T, dy, _mm256_set1_pd(rc.eye.y()));
  const __m256d pz = _mm256_fmadd_pd(T, dz, _mm256_set1_pd(rc.eye.z()));
  // gradient_scale and the floor of kRelativeGradientFloor.
  const __m256d m =
      _mm256_max_pd(_mm256_max_pd(_mm256_andnot_pd(sign, px), _mm256_andnot_pd(sign, py)),
                    _mm256_andnot_pd(sign, pz));
  __m256d bound = zero;
  for (size_t k = rc.gradient_bound.size(); k-- > 0;)
    bound = _mm256_fmadd_pd(bound, m, _mm256_load_pd(rc.gradient_bound4[k]));
  const __m256d floor = _mm256_mul_pd(_mm256_set1_pd(kRelativeGradientFloor), bound);
  // row_derivatives and row_gradient.
  const __m256d x = _mm256_mul_pd(
      T, _mm256_max_pd(_mm256_max_pd(_mm256_andnot_pd(sign, dx), _mm256_andnot_pd(sign, dy)),
                       _mm256_andnot_pd(sign, dz)));
  __m256d a = zero, b = zero, c = zero, e = zero;
  for (int k = D; k >= 1; --k) {
    a = _mm256_fmadd_pd(a, T, _mm256_mul_pd(_mm256_set1_pd(k), _mm256_load_pd(rc.packet_ck[k])));
    e = _mm256_fmadd_pd(e, x, _mm256_load_pd(rc.k_band4[k]));
    const double(*r)[4] = rc.row_ds4 + k * (k - 1) / 2;
    __m256d v = _mm256_load_pd(r[k - 1]);
    for (int j = k - 2; j >= 0; --j) v = _mm256_fmadd_pd(v, S, _mm256_load_pd(r[j]));
    b = _mm256_fmadd_pd(b, T, v);
  }
  for (int k = D - 1; k >= 0; --k) {
    const double(*r)[4] = rc.normal_row4 + k * (k + 1) / 2;
    __m256d v = _mm256_load_pd(r[k]);
    for (int j = k - 1; j >= 0; --j) v = _mm256_fmadd_pd(v, S, _mm256_load_pd(r[j]));
    c = _mm256_fmadd_pd(c, T, v);
  }
  const __m256d ss = _mm256_set1_pd(rc.row_ss), inn = _mm256_set1_pd(rc.row_inverse_nn);
  const __m256d dd = _mm256_fmadd_pd(dz, dz, _mm256_fmadd_pd(dy, dy, _mm256_mul_pd(dx, dx)));
  const __m256d ds = _mm256_fmadd_pd(S, ss, _mm256_set1_pd(rc.row_dot));
  const __m256d p = _mm256_mul_pd(_mm256_fmsub_pd(a, ss, _mm256_mul_pd(b, ds)), inn);
  const __m256d q = _mm256_mul_pd(_mm256_fmsub_pd(b, dd, _mm256_mul_pd(a, ds)), inn);
  const __m256d r = _mm256_mul_pd(c, inn);
  const __m256d gx =
      _mm256_fmadd_pd(r, _mm256_set1_pd(rc.row_normal.x()),
                      _mm256_fmadd_pd(q, _mm256_set1_pd(rc.step.x()), _mm256_mul_pd(p, dx)));
  const __m256d gy =
      _mm256_fmadd_pd(r, _mm256_set1_pd(rc.row_normal.y()),
                      _mm256_fmadd_pd(q, _mm256_set1_pd(rc.step.y()), _mm256_mul_pd(p, dy)));
  const __m256d gz =
      _mm256_fmadd_pd(r, _mm256_set1_pd(rc.row_normal.z()),
                      _mm256_fmadd_pd(q, _mm256_set1_pd(rc.step.z()), _mm256_mul_pd(p, dz)));
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
  const __m256d k = _mm256_div_pd(_mm256_blendv_pd(_mm256_set1_pd(1.0), _mm256_set1_pd(-1.0),
                                                   _mm256_cmp_pd(gd, zero, _CMP_GT_OQ)),
                                  _mm256_sqrt_pd(g2));
  const __m256d side = _mm256_load_pd(rc.packet_side.data());
  const __m256d front =
      _mm256_blendv_pd(_mm256_cmp_pd(gd, zero, _CMP_LT_OQ), _mm256_cmp_pd(side, zero, _CMP_GT_OQ),
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
    h.t = rc.packet_t[static_cast<size_t>(i)];
    h.point = Vec3(out[0][i], out[1][i], out[2][i]);
    h.normal = Vec3(out[3][i], out[4][i], out[5][i]);
    h.front = (front_bits >> i) & 1;
    h.singular = false;
  }
  return done;
}
#endif

}  // namespace

/// See SurfaceRayCaster::prepare_in_row.
int prepare(RayCaster& rc, std::span<const double> s) {
  rc.packet_size = 0;
  rc.packet_ready = false;
  rc.packet_hit_bits = rc.packet_done_bits = 0;
  if (s.size() != 4 || rc.parallel) return 0;
  std::copy(s.begin(), s.end(), rc.packet_s.begin());
  rc.packet_size = 4;
  rc.packet_next = 0;
#if defined(__AVX2__) && defined(__FMA__)
  if (!rc.exact) return 0;
  switch (rc.degree) {
    case 1:
      return prepare4<1>(rc, s.data());
    case 2:
      return prepare4<2>(rc, s.data());
    case 3:
      return prepare4<3>(rc, s.data());
    case 4:
      return prepare4<4>(rc, s.data());
    case 5:
      return prepare4<5>(rc, s.data());
    case 6:
      return prepare4<6>(rc, s.data());
    default:
      break;  // degrees above 6 are set up ray by ray
  }
#endif
  return 0;
}

/// The hits of the packet's rays that first_hit_in_row found (bit i: lane i hit).
int packet_hits(RayCaster& rc, SurfaceHit (&hits)[4]) {
  int remaining = rc.packet_hit_bits & ~rc.packet_done_bits;
#if defined(__AVX2__) && defined(__FMA__)
  if (remaining != 0 && rc.packet_ready && rc.has_row_normals) {
    switch (rc.degree) {
      case 1:
        remaining &= ~complete4<1>(rc, remaining, hits);
        break;
      case 2:
        remaining &= ~complete4<2>(rc, remaining, hits);
        break;
      case 3:
        remaining &= ~complete4<3>(rc, remaining, hits);
        break;
      case 4:
        remaining &= ~complete4<4>(rc, remaining, hits);
        break;
      case 5:
        remaining &= ~complete4<5>(rc, remaining, hits);
        break;
      case 6:
        remaining &= ~complete4<6>(rc, remaining, hits);
        break;
      default:
        break;
    }
  }
#endif
  for (int i = 0; i < 4; ++i) {
    const size_t lane = static_cast<size_t>(i);
    if ((rc.packet_done_bits >> i) & 1) hits[i] = rc.packet_done[lane];
    if (!((remaining >> i) & 1)) continue;
    // Where the row's gradient is not used: ∇F from F's terms, as for single rays.
    rc.ray_coeffs = lane_coeffs(rc, i);
    complete(rc, rc.packet_s[lane], rc.packet_t[lane], static_cast<int>(rc.packet_side[lane]),
             hits[i]);
  }
  const int bits = rc.packet_hit_bits;
  rc.packet_hit_bits = rc.packet_done_bits = 0;
  return bits;
}

}  // namespace zeroset::detail
