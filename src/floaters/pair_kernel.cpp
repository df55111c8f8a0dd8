#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numbers>

#include "pair_kernel_detail.h"
#include "rng_detail.h"

#ifdef ZS_PAIR_LANES4
#include <immintrin.h>
#endif

namespace zeroset::detail {
namespace {

// The pairs' term arrays are padded to whole groups of four.
constexpr std::size_t kLanes = 4;

bool has_normal(const double* record) {
  return !(record[5] == 0 && record[6] == 0 && record[7] == 0);
}

// The terms of the pair of floaters at slots s (i) and t (j), both ways.
template <bool kScaled>
PairTermsBoth<double> one_pair(const PairConstants& k, const double* records,
                               const std::uint64_t* ids, std::uint32_t s, std::uint32_t t) {
  const double* me = records + kRecordFields * s;
  const double* other = records + kRecordFields * t;
  const double si = me[3], sj = other[3];
  const double cosine = std::abs(dot3(me[5], me[6], me[7], other[5], other[6], other[7]));
  const double no_normal = has_normal(me) && has_normal(other) ? 0.0 : 1.0;
  const double dx = me[0] - other[0], dy = me[1] - other[1], dz = me[2] - other[2];
  const double d2 = dot3(dx, dy, dz, dx, dy, dz);
  const double larger = std::max(si, sj);
  if (!(d2 < 1e-18 * (larger * larger)))
    return pair_terms<kScaled>(dx, dy, dz, d2, std::sqrt(d2), si, sj, me[4], other[4], cosine,
                               no_normal, k);
  // Coincident: an offset r_ij of 10⁻³ the smaller radius in a direction from both ids (the
  // same whichever floater is listed first).
  const std::uint64_t a = ids[s], b = ids[t];
  const std::uint64_t lo = std::min(a, b), hi = std::max(a, b);
  const std::uint64_t h = mix64(lo * 0x9e3779b97f4a7c15ULL ^ hi);
  const double sign = a < b ? 1.0 : -1.0;
  const double angle = 2 * std::numbers::pi * static_cast<double>(h >> 11) * 0x1.0p-53;
  const double size = sign * 1e-3 * std::min(si, sj);
  const double ox = size * std::cos(angle), oy = size * std::sin(angle);
  const double o2 = dot3(ox, oy, 0.0, ox, oy, 0.0);
  return pair_terms<kScaled>(ox, oy, 0.0, o2, std::sqrt(o2), si, sj, me[4], other[4], cosine,
                             no_normal, k);
}

using Terms = PairBatch::Terms;

Terms record_of(const PairTerms<double>& r) { return {r.e, r.de, r.fx, r.fy, r.fz, r.lim, 0, 0}; }

template <bool kScaled>
void terms_scalar(const PairConstants& k, const double* records, const std::uint64_t* ids,
                  std::size_t m, const std::uint32_t* i, const std::uint32_t* j, Terms* out) {
  for (std::size_t q = 0; q < m; ++q) {
    const PairTermsBoth<double> both = one_pair<kScaled>(k, records, ids, i[q], j[q]);
    out[2 * q] = record_of(both.i);
    out[2 * q + 1] = record_of(both.j);
  }
}

#ifdef ZS_PAIR_LANES4
// Fields of four records, transposed into lane vectors: x, y, z, σ, σ_max, nx, ny, nz.
__attribute__((target("avx2,fma"), always_inline)) inline void transpose(const double* records,
                                                                         const std::uint32_t* slot,
                                                                         Double4* f) {
  for (int half = 0; half < 2; ++half) {
    const double* r = records + 4 * half;
    const __m256d a = _mm256_load_pd(r + kRecordFields * slot[0]);
    const __m256d b = _mm256_load_pd(r + kRecordFields * slot[1]);
    const __m256d c = _mm256_load_pd(r + kRecordFields * slot[2]);
    const __m256d d = _mm256_load_pd(r + kRecordFields * slot[3]);
    const __m256d ab_even = _mm256_unpacklo_pd(a, b), ab_odd = _mm256_unpackhi_pd(a, b);
    const __m256d cd_even = _mm256_unpacklo_pd(c, d), cd_odd = _mm256_unpackhi_pd(c, d);
    f[4 * half + 0] = _mm256_permute2f128_pd(ab_even, cd_even, 0x20);
    f[4 * half + 1] = _mm256_permute2f128_pd(ab_odd, cd_odd, 0x20);
    f[4 * half + 2] = _mm256_permute2f128_pd(ab_even, cd_even, 0x31);
    f[4 * half + 3] = _mm256_permute2f128_pd(ab_odd, cd_odd, 0x31);
  }
}

// Four pairs at a time, the lanes exactly as the scalar path computes each; the few (nearly)
// coincident pairs are then computed again by the scalar path, which separates them. m must
// be a multiple of four.
template <bool kScaled>
__attribute__((target("avx2,fma"))) void terms_avx2(const PairConstants& k, const double* records,
                                                    const std::uint64_t* ids, std::size_t m,
                                                    const std::uint32_t* i, const std::uint32_t* j,
                                                    Terms* out) {
  const Double4 zero = splat<Double4>(0.0), one = splat<Double4>(1.0);
  for (std::size_t q = 0; q < m; q += kLanes) {
    Double4 a[kRecordFields], b[kRecordFields];  // floaters i and j of the four pairs
    transpose(records, i + q, a);
    transpose(records, j + q, b);
    const Double4 dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    const Double4 d2 = dot3(dx, dy, dz, dx, dy, dz);
    const Double4 si = a[3], sj = b[3];
    const Double4 cosine = magnitude(dot3(a[5], a[6], a[7], b[5], b[6], b[7]));
    const Mask4 free_i = (a[5] == zero) & (a[6] == zero) & (a[7] == zero);
    const Mask4 free_j = (b[5] == zero) & (b[6] == zero) & (b[7] == zero);
    const Double4 no_normal = (free_i | free_j) ? one : zero;
    const PairTermsBoth<Double4> r = pair_terms<kScaled>(dx, dy, dz, d2, _mm256_sqrt_pd(d2), si, sj,
                                                         a[4], b[4], cosine, no_normal, k);
    // Lane vectors back to one record per pair and floater: four 4×4 transposes.
    for (int side = 0; side < 2; ++side) {
      const PairTerms<Double4>& t = side == 0 ? r.i : r.j;
      const Double4 rows[2][4] = {{t.e, t.de, t.fx, t.fy}, {t.fz, t.lim, zero, zero}};
      for (int half = 0; half < 2; ++half) {
        const Double4* v = rows[half];
        const __m256d lo01 = _mm256_unpacklo_pd(v[0], v[1]);
        const __m256d hi01 = _mm256_unpackhi_pd(v[0], v[1]);
        const __m256d lo23 = _mm256_unpacklo_pd(v[2], v[3]);
        const __m256d hi23 = _mm256_unpackhi_pd(v[2], v[3]);
        double* o = &out[2 * q + side].e + 4 * half;
        constexpr std::size_t kStride = 2 * sizeof(Terms) / sizeof(double);
        _mm256_store_pd(o, _mm256_permute2f128_pd(lo01, lo23, 0x20));
        _mm256_store_pd(o + kStride, _mm256_permute2f128_pd(hi01, hi23, 0x20));
        _mm256_store_pd(o + 2 * kStride, _mm256_permute2f128_pd(lo01, lo23, 0x31));
        _mm256_store_pd(o + 3 * kStride, _mm256_permute2f128_pd(hi01, hi23, 0x31));
      }
    }
    const Double4 larger = si < sj ? sj : si;
    const int coincident =
        _mm256_movemask_pd(std::bit_cast<Double4>(d2 < 1e-18 * (larger * larger)));
    for (int lane = 0; lane < 4; ++lane)
      if (coincident >> lane & 1) {
        const PairTermsBoth<double> both =
            one_pair<kScaled>(k, records, ids, i[q + lane], j[q + lane]);
        out[2 * (q + lane)] = record_of(both.i);
        out[2 * (q + lane) + 1] = record_of(both.j);
      }
  }
}
#endif

// The pairs (self, slots[near[q]]) for q < kept, written to i[q] and j[q].
void list_pairs_scalar(std::uint32_t* i, std::uint32_t* j, std::uint32_t self,
                       const std::uint32_t* slots, const std::uint32_t* near, std::size_t kept) {
  for (std::size_t q = 0; q < kept; ++q) {
    i[q] = self;
    j[q] = slots[near[q]];
  }
}

#ifdef ZS_PAIR_LANES4
// The same, eight at a time: lanes past `kept` neither read, and written with whatever (i and
// j need room for whole groups of eight).
__attribute__((target("avx2"))) void list_pairs_avx2(std::uint32_t* i, std::uint32_t* j,
                                                     std::uint32_t self, const std::uint32_t* slots,
                                                     const std::uint32_t* near, std::size_t kept) {
  const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i own = _mm256_set1_epi32(static_cast<int>(self));
  for (std::size_t q = 0; q < kept; q += 8) {
    const __m256i mask = _mm256_cmpgt_epi32(
        _mm256_set1_epi32(static_cast<int>(std::min<std::size_t>(kept - q, 8))), lane);
    const __m256i index = _mm256_maskload_epi32(reinterpret_cast<const int*>(near + q), mask);
    const __m256i slot = _mm256_mask_i32gather_epi32(
        _mm256_setzero_si256(), reinterpret_cast<const int*>(slots), index, mask, 4);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(j + q), slot);
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(i + q), own);
  }
}
#endif

// Adds the terms of pairs [0, m) (out, two per pair) to the sums, in the order of
// PairBatch::accumulate(): a floater's pairs are listed together, so its own terms are summed
// in registers, then added to its sums once (none of its pairs has it as the other floater).
template <bool kGraded>
void sum_terms_scalar(const Terms* out, const std::uint32_t* i, const std::uint32_t* j,
                      std::size_t m, PairSums* sums) {
  const auto add = [](PairSums& s, const Terms& t) {
    s.e += t.e;
    s.de += t.de;
    s.vx += t.fx;
    s.vy += t.fy;
    s.vz += t.fz;
    if (kGraded) s.limit = t.lim < s.limit ? t.lim : s.limit;
  };
  for (std::size_t q = 0; q < m;) {
    const std::uint32_t self = i[q];
    PairSums own{0, 0, 0, 0, 0, std::numeric_limits<double>::infinity()};
    for (; q < m && i[q] == self; ++q) {
      add(own, out[2 * q]);
      add(sums[j[q]], out[2 * q + 1]);
    }
    PairSums& total = sums[self];
    total.e += own.e;
    total.de += own.de;
    total.vx += own.vx;
    total.vy += own.vy;
    total.vz += own.vz;
    total.limit = std::min(total.limit, own.limit);
  }
}

#ifdef ZS_PAIR_LANES4
// The same sums, the first four fields of a record (e, de, fx, fy) in one vector: each lane
// adds exactly as the scalar path, in the same order.
template <bool kGraded>
__attribute__((target("avx2"))) void sum_terms_avx2(const Terms* out, const std::uint32_t* i,
                                                    const std::uint32_t* j, std::size_t m,
                                                    PairSums* sums) {
  static_assert(offsetof(PairSums, vz) == 4 * sizeof(double));
  for (std::size_t q = 0; q < m;) {
    const std::uint32_t self = i[q];
    __m256d own = _mm256_setzero_pd();
    __m128d own_z = _mm_setzero_pd();
    __m128d own_limit = _mm_set_sd(std::numeric_limits<double>::infinity());
    for (; q < m && i[q] == self; ++q) {
      const double* mine = &out[2 * q].e;
      own = _mm256_add_pd(own, _mm256_load_pd(mine));
      own_z = _mm_add_sd(own_z, _mm_load_sd(mine + 4));
      // minsd a, b is a < b ? a : b, as the scalar path's comparison.
      if (kGraded) own_limit = _mm_min_sd(_mm_load_sd(mine + 5), own_limit);
      const double* theirs = &out[2 * q + 1].e;
      double* sum = &sums[j[q]].e;
      _mm256_storeu_pd(sum, _mm256_add_pd(_mm256_loadu_pd(sum), _mm256_load_pd(theirs)));
      sum[4] += theirs[4];
      if (kGraded) sum[5] = theirs[5] < sum[5] ? theirs[5] : sum[5];
    }
    double* total = &sums[self].e;
    _mm256_storeu_pd(total, _mm256_add_pd(_mm256_loadu_pd(total), own));
    total[4] += _mm_cvtsd_f64(own_z);
    total[5] = std::min(total[5], _mm_cvtsd_f64(own_limit));
  }
}
#endif

}  // namespace

void PairBatch::add(std::uint32_t self, const std::uint32_t* slots, const std::uint32_t* near,
                    std::size_t kept) {
  const std::size_t first = pairs_;
  // Room for the pairs, a whole group of eight past them (list_pairs_avx2) and the padding of
  // accumulate().
  if (j_.size() < first + kept + 8) {
    const std::size_t room = 2 * (first + kept + 8);
    i_.resize(room);
    j_.resize(room);
  }
#ifdef ZS_PAIR_LANES4
  if (path_ == FilterPath::kAvx2)
    list_pairs_avx2(i_.data() + first, j_.data() + first, self, slots, near, kept);
  else
#endif
    list_pairs_scalar(i_.data() + first, j_.data() + first, self, slots, near, kept);
  pairs_ = first + kept;
}

void PairBatch::accumulate(bool scaled, const PairConstants& k, const double* records,
                           const std::uint64_t* ids, std::span<PairSums> sums) {
  const std::size_t m = pairs_;
  if (m == 0) return;
  // Padded to whole groups with copies of a real pair, whose terms are not used.
  const std::size_t padded = (m + kLanes - 1) / kLanes * kLanes;
  if (terms_.size() < 2 * padded) terms_.resize(4 * padded);
  Terms* out = terms_.data();
#ifdef ZS_PAIR_LANES4
  if (path_ == FilterPath::kAvx2) {
    std::fill(i_.begin() + static_cast<std::ptrdiff_t>(m),
              i_.begin() + static_cast<std::ptrdiff_t>(padded), i_[0]);
    std::fill(j_.begin() + static_cast<std::ptrdiff_t>(m),
              j_.begin() + static_cast<std::ptrdiff_t>(padded), j_[0]);
    (scaled ? terms_avx2<true> : terms_avx2<false>)(k, records, ids, padded, i_.data(), j_.data(),
                                                    out);
  } else
#endif
  {
    (scaled ? terms_scalar<true> : terms_scalar<false>)(k, records, ids, m, i_.data(), j_.data(),
                                                        out);
  }
  const bool graded = k.grading > 0;
#ifdef ZS_PAIR_LANES4
  if (path_ == FilterPath::kAvx2) {
    (graded ? sum_terms_avx2<true> : sum_terms_avx2<false>)(out, i_.data(), j_.data(), m,
                                                            sums.data());
  } else
#endif
  {
    (graded ? sum_terms_scalar<true> : sum_terms_scalar<false>)(out, i_.data(), j_.data(), m,
                                                                sums.data());
  }
  pairs_ = 0;
}

}  // namespace zeroset::detail
