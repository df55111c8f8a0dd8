#include <algorithm>

#include "neighbour_filter_detail.h"

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define ZS_FILTER_X86 1
#endif

namespace zeroset::detail {
namespace {

#ifdef ZS_FILTER_X86
// For every mask of `kLanes` lanes: the positions of its set bits, in order, and how many. Adding
// the positions to a group's first index and storing all kLanes of them lists the group's kept
// indices without a branch (the count says how many of the stored ones are real).
template <int kLanes>
struct LaneTable {
  alignas(32) std::uint32_t offsets[1 << kLanes][kLanes] = {};
  std::uint8_t count[1 << kLanes] = {};

  constexpr LaneTable() {
    for (int mask = 0; mask < (1 << kLanes); ++mask) {
      int c = 0;
      for (int lane = 0; lane < kLanes; ++lane)
        if (mask & (1 << lane)) offsets[mask][c++] = static_cast<std::uint32_t>(lane);
      count[mask] = static_cast<std::uint8_t>(c);
    }
  }
};
constexpr LaneTable<4> kLanes4;
constexpr LaneTable<8> kLanes8;

// Lanes of a group starting at t that lie before `last`.
template <int kLanes>
unsigned lanes_in_range(std::uint32_t t, std::uint32_t last) {
  const std::uint32_t left = last - t;
  return left >= kLanes ? (1u << kLanes) - 1 : (1u << left) - 1;
}

__attribute__((target("avx2"))) std::size_t filter_avx2(std::span<const SpatialHash::Range> ranges,
                                                        const float* x, const float* y,
                                                        const float* z, const float* cut, float px,
                                                        float py, float pz, float p_cut,
                                                        std::uint32_t* out) {
  const __m256 vx = _mm256_set1_ps(px), vy = _mm256_set1_ps(py), vz = _mm256_set1_ps(pz);
  const __m256 vcut = _mm256_set1_ps(p_cut);
  std::size_t m = 0;
  for (const auto& [first, last] : ranges)
    for (std::uint32_t t = first; t < last; t += 8) {
      const __m256 dx = _mm256_sub_ps(vx, _mm256_loadu_ps(x + t));
      const __m256 dy = _mm256_sub_ps(vy, _mm256_loadu_ps(y + t));
      const __m256 dz = _mm256_sub_ps(vz, _mm256_loadu_ps(z + t));
      const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                      _mm256_mul_ps(dz, dz));
      const __m256 reach = _mm256_max_ps(vcut, _mm256_loadu_ps(cut + t));
      const unsigned mask =
          static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(d2, reach, _CMP_LT_OQ))) &
          lanes_in_range<8>(t, last);
      const __m256i offsets =
          _mm256_load_si256(reinterpret_cast<const __m256i*>(kLanes8.offsets[mask]));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + m),
                          _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(t)), offsets));
      m += kLanes8.count[mask];
    }
  return m;
}

std::size_t filter_sse2(std::span<const SpatialHash::Range> ranges, const float* x, const float* y,
                        const float* z, const float* cut, float px, float py, float pz, float p_cut,
                        std::uint32_t* out) {
  const __m128 vx = _mm_set1_ps(px), vy = _mm_set1_ps(py), vz = _mm_set1_ps(pz);
  const __m128 vcut = _mm_set1_ps(p_cut);
  std::size_t m = 0;
  for (const auto& [first, last] : ranges)
    for (std::uint32_t t = first; t < last; t += 4) {
      const __m128 dx = _mm_sub_ps(vx, _mm_loadu_ps(x + t));
      const __m128 dy = _mm_sub_ps(vy, _mm_loadu_ps(y + t));
      const __m128 dz = _mm_sub_ps(vz, _mm_loadu_ps(z + t));
      const __m128 d2 =
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
      const __m128 reach = _mm_max_ps(vcut, _mm_loadu_ps(cut + t));
      const unsigned mask = static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(d2, reach))) &
                            lanes_in_range<4>(t, last);
      const __m128i offsets =
          _mm_load_si128(reinterpret_cast<const __m128i*>(kLanes4.offsets[mask]));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + m),
                       _mm_add_epi32(_mm_set1_epi32(static_cast<int>(t)), offsets));
      m += kLanes4.count[mask];
    }
  return m;
}

__attribute__((target("avx2"))) std::size_t box_avx2(std::span<const SpatialHash::Range> ranges,
                                                     const float* x, const float* y, const float* z,
                                                     const float* cut, const float* lo,
                                                     const float* hi, float reach,
                                                     std::uint32_t* out) {
  const __m256 lox = _mm256_set1_ps(lo[0]), loy = _mm256_set1_ps(lo[1]);
  const __m256 loz = _mm256_set1_ps(lo[2]), hix = _mm256_set1_ps(hi[0]);
  const __m256 hiy = _mm256_set1_ps(hi[1]), hiz = _mm256_set1_ps(hi[2]);
  const __m256 vreach = _mm256_set1_ps(reach), zero = _mm256_setzero_ps();
  std::size_t m = 0;
  for (const auto& [first, last] : ranges)
    for (std::uint32_t t = first; t < last; t += 8) {
      const __m256 px = _mm256_loadu_ps(x + t), py = _mm256_loadu_ps(y + t);
      const __m256 pz = _mm256_loadu_ps(z + t);
      const __m256 dx =
          _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(lox, px), _mm256_sub_ps(px, hix)), zero);
      const __m256 dy =
          _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(loy, py), _mm256_sub_ps(py, hiy)), zero);
      const __m256 dz =
          _mm256_max_ps(_mm256_max_ps(_mm256_sub_ps(loz, pz), _mm256_sub_ps(pz, hiz)), zero);
      const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                      _mm256_mul_ps(dz, dz));
      const __m256 limit = _mm256_max_ps(vreach, _mm256_loadu_ps(cut + t));
      const unsigned mask =
          static_cast<unsigned>(_mm256_movemask_ps(_mm256_cmp_ps(d2, limit, _CMP_LT_OQ))) &
          lanes_in_range<8>(t, last);
      const __m256i offsets =
          _mm256_load_si256(reinterpret_cast<const __m256i*>(kLanes8.offsets[mask]));
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + m),
                          _mm256_add_epi32(_mm256_set1_epi32(static_cast<int>(t)), offsets));
      m += kLanes8.count[mask];
    }
  return m;
}

std::size_t box_sse2(std::span<const SpatialHash::Range> ranges, const float* x, const float* y,
                     const float* z, const float* cut, const float* lo, const float* hi,
                     float reach, std::uint32_t* out) {
  const __m128 lox = _mm_set1_ps(lo[0]), loy = _mm_set1_ps(lo[1]), loz = _mm_set1_ps(lo[2]);
  const __m128 hix = _mm_set1_ps(hi[0]), hiy = _mm_set1_ps(hi[1]), hiz = _mm_set1_ps(hi[2]);
  const __m128 vreach = _mm_set1_ps(reach), zero = _mm_setzero_ps();
  std::size_t m = 0;
  for (const auto& [first, last] : ranges)
    for (std::uint32_t t = first; t < last; t += 4) {
      const __m128 px = _mm_loadu_ps(x + t), py = _mm_loadu_ps(y + t), pz = _mm_loadu_ps(z + t);
      const __m128 dx = _mm_max_ps(_mm_max_ps(_mm_sub_ps(lox, px), _mm_sub_ps(px, hix)), zero);
      const __m128 dy = _mm_max_ps(_mm_max_ps(_mm_sub_ps(loy, py), _mm_sub_ps(py, hiy)), zero);
      const __m128 dz = _mm_max_ps(_mm_max_ps(_mm_sub_ps(loz, pz), _mm_sub_ps(pz, hiz)), zero);
      const __m128 d2 =
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
      const __m128 limit = _mm_max_ps(vreach, _mm_loadu_ps(cut + t));
      const unsigned mask = static_cast<unsigned>(_mm_movemask_ps(_mm_cmplt_ps(d2, limit))) &
                            lanes_in_range<4>(t, last);
      const __m128i offsets =
          _mm_load_si128(reinterpret_cast<const __m128i*>(kLanes4.offsets[mask]));
      _mm_storeu_si128(reinterpret_cast<__m128i*>(out + m),
                       _mm_add_epi32(_mm_set1_epi32(static_cast<int>(t)), offsets));
      m += kLanes4.count[mask];
    }
  return m;
}

#endif

std::size_t filter_scalar(std::span<const SpatialHash::Range> ranges, const float* x,
                          const float* y, const float* z, const float* cut, float px, float py,
                          float pz, float p_cut, std::uint32_t* out) {
  std::size_t m = 0;
  for (const auto& [first, last] : ranges)
    for (std::uint32_t t = first; t < last; ++t) {
      const float dx = px - x[t], dy = py - y[t], dz = pz - z[t];
      out[m] = t;
      m += (dx * dx + dy * dy) + dz * dz < std::max(p_cut, cut[t]);
    }
  return m;
}

std::size_t box_scalar(std::span<const SpatialHash::Range> ranges, const float* x, const float* y,
                       const float* z, const float* cut, const float* lo, const float* hi,
                       float reach, std::uint32_t* out) {
  std::size_t m = 0;
  for (const auto& [first, last] : ranges)
    for (std::uint32_t t = first; t < last; ++t) {
      const float dx = std::max(std::max(lo[0] - x[t], x[t] - hi[0]), 0.0f);
      const float dy = std::max(std::max(lo[1] - y[t], y[t] - hi[1]), 0.0f);
      const float dz = std::max(std::max(lo[2] - z[t], z[t] - hi[2]), 0.0f);
      out[m] = t;
      m += (dx * dx + dy * dy) + dz * dz < std::max(reach, cut[t]);
    }
  return m;
}

}  // namespace

bool filter_path_available(FilterPath path) {
  switch (path) {
    case FilterPath::kScalar:
      return true;
#ifdef ZS_FILTER_X86
    case FilterPath::kSse2:
      return true;
    case FilterPath::kAvx2: {
      static const bool avx2 = [] {
        __builtin_cpu_init();
        return __builtin_cpu_supports("avx2") != 0 && __builtin_cpu_supports("fma") != 0;
      }();
      return avx2;
    }
#else
    case FilterPath::kSse2:
    case FilterPath::kAvx2:
      return false;
#endif
  }
  return false;
}

FilterPath best_filter_path() {
  for (FilterPath path : {FilterPath::kAvx2, FilterPath::kSse2})
    if (filter_path_available(path)) return path;
  return FilterPath::kScalar;
}

std::size_t filter_near(FilterPath path, std::span<const SpatialHash::Range> ranges, const float* x,
                        const float* y, const float* z, const float* cut, float px, float py,
                        float pz, float p_cut, std::uint32_t* out) {
  switch (path) {
#ifdef ZS_FILTER_X86
    case FilterPath::kAvx2:
      return filter_avx2(ranges, x, y, z, cut, px, py, pz, p_cut, out);
    case FilterPath::kSse2:
      return filter_sse2(ranges, x, y, z, cut, px, py, pz, p_cut, out);
#endif
    default:
      return filter_scalar(ranges, x, y, z, cut, px, py, pz, p_cut, out);
  }
}

std::size_t filter_box(FilterPath path, std::span<const SpatialHash::Range> ranges, const float* x,
                       const float* y, const float* z, const float* cut, const float* lo,
                       const float* hi, float reach, std::uint32_t* out) {
  switch (path) {
#ifdef ZS_FILTER_X86
    case FilterPath::kAvx2:
      return box_avx2(ranges, x, y, z, cut, lo, hi, reach, out);
    case FilterPath::kSse2:
      return box_sse2(ranges, x, y, z, cut, lo, hi, reach, out);
#endif
    default:
      return box_scalar(ranges, x, y, z, cut, lo, hi, reach, out);
  }
}

}  // namespace zeroset::detail
