// Sampling F at rows of grid nodes and taking their sign bits (row_sampling_detail.h).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <span>

#if defined(__AVX__)
#include <immintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "row_sampling_detail.h"
#include "zeroset/detail/bracket.h"

namespace zeroset::detail {
namespace {

// Bit i of bits[i / 64] set where values[i] counts as positive (is_positive); returns how many
// values are not finite (NaN or infinite: v − v is NaN for both). Four (AVX) or two (SSE2) values
// per compare where available.
long long sign_bits(const double* values, long long n, std::uint64_t* bits) {
  long long nans = 0;
  for (long long b = 0; b < n; b += 64) {
    const long long e = std::min(n, b + 64);
    std::uint64_t word = 0;
    long long i = b;
#if defined(__AVX__)
    __m256d unordered = _mm256_setzero_pd();
    for (; i + 4 <= e; i += 4) {
      const __m256d v = _mm256_loadu_pd(values + i);
      // not (v < 0), true for NaN: NaN counts as positive
      const auto positive = static_cast<std::uint64_t>(
          _mm256_movemask_pd(_mm256_cmp_pd(v, _mm256_setzero_pd(), _CMP_NLT_UQ)));
      word |= positive << (i - b);
      const __m256d d = _mm256_sub_pd(v, v);
      unordered = _mm256_or_pd(unordered, _mm256_cmp_pd(d, d, _CMP_UNORD_Q));
    }
    if (_mm256_movemask_pd(unordered))  // rare: count them one by one
      for (long long q = b; q < i; ++q) nans += std::isfinite(values[q]) ? 0 : 1;
#elif defined(__SSE2__)
    const __m128d zero = _mm_setzero_pd();
    __m128d unordered = _mm_setzero_pd();
    for (; i + 2 <= e; i += 2) {
      const __m128d v = _mm_loadu_pd(values + i);
      // not (v < 0): NaN counts as positive
      const auto positive = static_cast<std::uint64_t>(~_mm_movemask_pd(_mm_cmplt_pd(v, zero)) & 3);
      word |= positive << (i - b);
      const __m128d d = _mm_sub_pd(v, v);
      unordered = _mm_or_pd(unordered, _mm_cmpunord_pd(d, d));
    }
    if (_mm_movemask_pd(unordered))  // rare: count them one by one
      for (long long q = b; q < i; ++q) nans += std::isfinite(values[q]) ? 0 : 1;
#endif
    for (; i < e; ++i) {
      word |= static_cast<std::uint64_t>(is_positive(values[i])) << (i - b);
      nans += std::isfinite(values[i]) ? 0 : 1;
    }
    bits[b / 64] = word;
  }
  return nans;
}

}  // namespace

RowSampler::RowSampler(const Field& field, const Grid& grid, const Polynomial* poly) : grid_(grid) {
  if (!poly) {
    eval_.emplace(field);
    return;
  }
  line_.emplace(*poly, grid, 0);
  coeffs_.resize(static_cast<size_t>(std::max(0, line_->degree()) + 1));
  t_.resize(static_cast<size_t>(grid_.nx()));
  for (long long i = 0; i < grid_.nx(); ++i) t_[static_cast<size_t>(i)] = line_->t_of(i);
}

long long RowSampler::sample(long long i0, long long count, long long j, long long k, double* out,
                             std::uint64_t* bits) {
  if (line_ && line_->degree() >= 0) {
    line_->coefficients(grid_.coord(1, j), grid_.coord(2, k), coeffs_.data());
    // Horner's rule on blocks of nodes held in registers; every node sees the same
    // operations in the same order (fused multiply-adds where the processor has them),
    // whichever block it falls in, so a node's value does not depend on the run.
    const int degree = line_->degree();
    const double* t = &t_[static_cast<size_t>(i0)];
    const double* c = coeffs_.data();
    long long n = 0;
#if defined(__AVX2__) && defined(__FMA__)
    // The sign bits come from the registers too: sixteen nodes are a quarter word.
    long long nans = 0;
    if (bits) std::fill(bits, bits + (count + 63) / 64, 0);
    // Four independent chains of four nodes hide the latency of the multiply-adds.
    for (; n + 16 <= count; n += 16) {
      __m256d acc[4], tt[4];
      for (int q = 0; q < 4; ++q)
        acc[q] = _mm256_set1_pd(c[degree]), tt[q] = _mm256_loadu_pd(t + n + 4 * q);
      for (int m = degree - 1; m >= 0; --m) {
        const __m256d cm = _mm256_set1_pd(c[m]);
        for (int q = 0; q < 4; ++q) acc[q] = _mm256_fmadd_pd(acc[q], tt[q], cm);
      }
      for (int q = 0; q < 4; ++q) _mm256_storeu_pd(out + n + 4 * q, acc[q]);
      if (!bits) continue;
      std::uint64_t positive = 0;
      __m256d unordered = _mm256_setzero_pd();
      for (int q = 0; q < 4; ++q) {
        // not (v < 0), true for NaN: NaN counts as positive
        positive |= static_cast<std::uint64_t>(
                        _mm256_movemask_pd(_mm256_cmp_pd(acc[q], _mm256_setzero_pd(), _CMP_NLT_UQ)))
                    << (4 * q);
        const __m256d d = _mm256_sub_pd(acc[q], acc[q]);  // NaN where not finite
        unordered = _mm256_or_pd(unordered, _mm256_cmp_pd(d, d, _CMP_UNORD_Q));
      }
      bits[n / 64] |= positive << (n % 64);
      if (_mm256_movemask_pd(unordered))  // rare (overflow): count them one by one
        for (long long q = n; q < n + 16; ++q) nans += std::isfinite(out[q]) ? 0 : 1;
    }
    for (; n < count; ++n) {
      double v = c[degree];
      for (int m = degree - 1; m >= 0; --m) v = std::fma(v, t[n], c[m]);
      out[n] = v;
      if (!bits) continue;
      bits[n / 64] |= static_cast<std::uint64_t>(is_positive(v)) << (n % 64);
      nans += std::isfinite(v) ? 0 : 1;
    }
    return nans;
#else
    for (; n < count; ++n) {
      double v = c[degree];
      for (int m = degree - 1; m >= 0; --m) v = v * t[n] + c[m];
      out[n] = v;
    }
#endif
  } else if (line_) {  // the zero polynomial
    std::fill(out, out + count, 0.0);
  } else {
    x_.resize(static_cast<size_t>(count));
    y_.assign(static_cast<size_t>(count), grid_.coord(1, j));
    z_.assign(static_cast<size_t>(count), grid_.coord(2, k));
    for (long long n = 0; n < count; ++n) x_[static_cast<size_t>(n)] = grid_.coord(0, i0 + n);
    eval_->values(x_, y_, z_, std::span<double>(out, static_cast<size_t>(count)));
  }
  return bits ? sign_bits(out, count, bits) : 0;
}

}  // namespace zeroset::detail
