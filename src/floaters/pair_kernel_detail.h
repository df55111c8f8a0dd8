#pragma once
// The floaters' neighbour (repulsion) pass, the part worth testing on its own: the terms of a pair
// of floaters, both ways at once, and their sums over each floater's neighbours, with an
// exponential written for it, and the single-precision prefilter threshold that never drops a pair
// within the cutoff. The pair terms are written once, for a lane type that is either a double or
// four doubles (GCC's vector extension, the AVX2 kernel's registers), with the same operations in
// the same order in both, so both give the same bits. Private to the floaters module.
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numbers>
#include <span>
#include <vector>

#include "neighbour_filter_detail.h"

#if defined(__x86_64__) && defined(__GNUC__)
#define ZS_PAIR_LANES4 1
#endif

namespace zeroset::detail {

// ---- lane types: what the formulas below need of a double and of four doubles ----------------

[[gnu::always_inline]] inline std::uint64_t to_bits(double v) {
  return std::bit_cast<std::uint64_t>(v);
}
[[gnu::always_inline]] inline double from_bits(std::uint64_t b) { return std::bit_cast<double>(b); }
template <class V>
[[gnu::always_inline]] inline V splat(double v) {
  return v;
}
/// a·b + c rounded once (a fused multiply-add), as the AVX2 lanes compute it. std::fma is one
/// instruction where the processor has FMA (every processor with AVX2), a library call
/// otherwise.
[[gnu::always_inline]] inline double mul_add(double a, double b, double c) {
  return std::fma(a, b, c);
}

#ifdef ZS_PAIR_LANES4
// Functions on these take AVX vectors by value and are always inlined into AVX2 code, so the
// warning that callers without AVX would pass them differently does not apply.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
// Four lanes. Arithmetic, comparisons (which give lane masks of all ones or zeros) and a ?: on
// a mask act lane by lane, each lane exactly as the scalar operation.
using Double4 = double __attribute__((vector_size(32)));
using Bits4 = std::uint64_t __attribute__((vector_size(32)));
using Mask4 = decltype(Double4{} < Double4{});
[[gnu::always_inline]] inline Bits4 to_bits(Double4 v) { return std::bit_cast<Bits4>(v); }
[[gnu::always_inline]] inline Double4 from_bits(Bits4 b) { return std::bit_cast<Double4>(b); }
template <>
[[gnu::always_inline]] inline Double4 splat<Double4>(double v) {
  return Double4{v, v, v, v};
}
// vfmadd231pd: c + a·b, rounded once. Assembly, not the intrinsic, because the formulas that
// call it are compiled for every processor; only the AVX2 path (which requires FMA) uses them on
// Double4, always inlined.
[[gnu::always_inline]] inline Double4 mul_add(Double4 a, Double4 b, Double4 c) {
  asm("vfmadd231pd %[b], %[a], %[c]" : [c] "+x"(c) : [a] "x"(a), [b] "x"(b));
  return c;
}
#pragma GCC diagnostic pop
#endif

/// |v|, by clearing the sign bit (as std::abs does).
template <class V>
[[gnu::always_inline]] inline V magnitude(V v) {
  return from_bits(to_bits(v) & 0x7fff'ffff'ffff'ffffULL);
}

/// e^a for a in [−4.5, 0], the range of every pair term inside the cutoff (|r| < 3σ gives
/// exponents above −9/2), with relative error below 1e-10: Cody–Waite reduction to
/// |r| ≤ ln2/2 and a degree-7 polynomial fitted at Chebyshev nodes (error 5.5e-11 on that
/// interval, by Horner's rule in fused multiply-adds). The pair energies need far less;
/// std::exp is exact to the last bit, but a call per pair cannot be vectorised and cost a sixth
/// of a step. Arguments below −64 are taken as −64
/// (those terms lie beyond the cutoff and are discarded); a NaN gives an unspecified value.
/// Branch-free and pure; for V a double or Double4, lane by lane.
template <class V>
[[gnu::always_inline]] inline V exp_cutoff(V a) {
  a = a < splat<V>(-64.0) ? splat<V>(-64.0) : a;
  // Adding 1.5·2^52 rounds a·log2(e) to the nearest integer k, which then sits in the low bits
  // of t; k << 52 added to the bits of p multiplies p by 2^k (k ≥ −93: no underflow).
  constexpr double kShift = 0x1.8p52;
  constexpr double kLn2Hi = 0x1.62e42feep-1;  // trailing zeros: k·kLn2Hi is exact
  constexpr double kLn2Lo = 0x1.a39ef35793c76p-33;
  const V t = mul_add(a, splat<V>(std::numbers::log2e), splat<V>(kShift));
  const V k = t - kShift;
  const V r = mul_add(k, splat<V>(-kLn2Lo), mul_add(k, splat<V>(-kLn2Hi), a));
  constexpr double kCoefficients[] = {
      0x1.6da753185ad01p-10, 0x1.1110a6222ea35p-7, 0x1.555464a0f079ep-5, 0x1.5555557e7125ep-3,
      0x1.0000005c89e4ep-1,  0x1.fffffffff61fdp-1, 0x1.ffffffffa7135p-1};
  V p = splat<V>(0x1.a17df2ec2bc60p-13);
  for (double c : kCoefficients) p = mul_add(p, r, splat<V>(c));
  return from_bits(to_bits(p) + (to_bits(t) << 52));
}

/// The neighbour prefilter compares squared distances in single precision, on coordinates
/// shifted and scaled into [−1, 1]. Each coordinate is then off by at most 2^-24, a float
/// difference by 2^-22, a distance by 2^-21, and the float sum of squares by a factor
/// 1 + 2^-21. So a pair closer than `reach` (in scaled units) always has a float squared
/// distance below this threshold: the prefilter only ever keeps too many pairs, never too few,
/// and the exact test in double precision after it decides.
inline float prefilter_threshold(double reach) {
  const double widened = reach * (1 + 0x1p-40) + 0x1p-21;
  // The factor covers the float rounding of the sum of squares and of the threshold itself.
  return static_cast<float>(widened * widened * (1 + 0x1p-18));
}

/// a·b for three-vectors given by their coordinates, as the pair terms take it (for |r|² and
/// the normals' cosine).
template <class V>
[[gnu::always_inline]] inline V dot3(V ax, V ay, V az, V bx, V by, V bz) {
  return mul_add(az, bz, mul_add(ay, by, ax * bx));
}

// ---- the pair terms and their sums -------------------------------------------------------------

/// The constants of the pair terms (the switch is a double, to be tested without a branch).
struct PairConstants {
  double alpha;       // α
  double cos_weight;  // 1: E_ij weighted by |cos(∇F_i, ∇F_j)|; 0: not
  double grading;     // g
  double taper = 1;   // 1: the factor (1 − |r|²/9σ²) of A.1; 0: the plain Gaussian
};

/// What one floater of a pair gets from the other: E_ij, |r|²·E_ij, the force along r_ij and
/// the grading limit.
template <class V>
struct PairTerms {
  V e, de, fx, fy, fz, lim;
};

/// The terms of a pair, for each of its floaters.
template <class V>
struct PairTermsBoth {
  PairTerms<V> i, j;
};

/// The terms of the pair of floaters i and j, both ways, with offset r_ij = (dx, dy, dz),
/// |r_ij|² = d2 and |r_ij| = dist, radii σ_i = si and σ_j = sj, fission radii σ_max = pi and
/// pj, |n_i·n_j| = cosine for their unit normals and `no_normal` 1 when either has none, else 0
/// (docs/algorithms.md A.1–A.2, B.1, and the scaled form, see FloaterOptions::scaled_repulsion).
/// The energies E_ij = αw·e^{−u}(1 − 2u/9) with u = |r|²/2σ_i² (cut off at u = 9/2), and E_ji
/// alike with σ_j. Forces along r_ij: scaled, 2(σ_i/σ_ij)·αw·e^{−x/2}(1 − x/9) with
/// x = |r|²/σ_ij², σ_ij = (σ_i + σ_j)/2, one exponential for both floaters; A.2,
/// E_ij + (σ_i/σ_j)² E_ji, whose E_ji is the other floater's energy: two exponentials in all.
/// A pair beyond reach 3·max(σ_i, σ_j) adds exactly nothing: no energy or force, and infinite
/// limits.
template <bool kScaled, class V>
[[gnu::always_inline]] inline PairTermsBoth<V> pair_terms(V dx, V dy, V dz, V d2, V dist, V si,
                                                          V sj, V pi, V pj, V cosine, V no_normal,
                                                          const PairConstants& k) {
  const V zero = splat<V>(0.0), one = splat<V>(1.0);
  // w_ij = |cos(∇F_i, ∇F_j)|, or 1 when either has no normal (then the cosine is exactly 0).
  const V w = k.cos_weight > 0 ? cosine + no_normal : one;
  const V reach_i = 9.0 * si * si, reach_j = 9.0 * sj * sj;
  const auto within = d2 < (reach_i < reach_j ? reach_j : reach_i);
  const V aw = within ? k.alpha * w : zero;
  const V ui = d2 * (1.0 / (2.0 * (si * si))), uj = d2 * (1.0 / (2.0 * (sj * sj)));
  // Both terms are finite for every listed pair; beyond its own cutoff each is dropped.
  // The taper's slopes; × 1 (the default) leaves them exactly −2/9 and −1/9.
  const V slope_u = splat<V>(-2.0 / 9 * k.taper), slope_x = splat<V>(-1.0 / 9 * k.taper);
  const V ei_all = aw * exp_cutoff(-ui) * mul_add(ui, slope_u, one);
  const V ej_all = aw * exp_cutoff(-uj) * mul_add(uj, slope_u, one);
  const V ei = ui < splat<V>(4.5) ? ei_all : zero;
  const V ej = uj < splat<V>(4.5) ? ej_all : zero;
  V coef_i, coef_j;
  if constexpr (kScaled) {
    const V inv = 2.0 / (si + sj);
    const V x = d2 * inv * inv;
    const V f_all = aw * exp_cutoff(-0.5 * x) * mul_add(x, slope_x, one);
    const V f = x < splat<V>(9.0) ? f_all : zero;
    coef_i = (2.0 * si * inv) * f;
    coef_j = (2.0 * sj * inv) * f;
  } else {
    const V ratio = si / sj;
    coef_i = mul_add(ratio * ratio, ej, ei);
    coef_j = mul_add(1.0 / (ratio * ratio), ei, ej);
  }
  const V far = splat<V>(std::numeric_limits<double>::infinity());
  const V lim_i = within ? mul_add(splat<V>(k.grading), dist, pj) : far;
  const V lim_j = within ? mul_add(splat<V>(k.grading), dist, pi) : far;
  return {{ei, d2 * ei, coef_i * dx, coef_i * dy, coef_i * dz, lim_i},
          {ej, d2 * ej, -(coef_j * dx), -(coef_j * dy), -(coef_j * dz), lim_j}};
}

/// Σ_j E_ij, Σ_j |r_ij|²·E_ij, the desired velocity Σ_j (force along r_ij), and the smallest
/// grading limit (or the floater's own limit if that is smaller).
struct PairSums {
  double e, de, vx, vy, vz, limit;
};

/// The pair terms of many pairs of floaters (pair_terms(), scaled or not), each pair listed
/// once and its terms added to both floaters' sums. Pairs are listed, then computed all at
/// once, four at a time whoever they belong to (independent work that keeps the processor's
/// pipelines full), then added to the sums in the order listed, so every path gives the same
/// bits, and a caller that lists the pairs of each floater in a fixed order gets sums that do
/// not depend on how the work was split.
///
/// A pair that is (nearly) coincident, |r_ij|² < 10⁻¹⁸ max(σ_i, σ_j)², feels no force along
/// r = 0: its terms are taken at a tiny offset along a direction both floaters derive from
/// their ids, so they separate.
class PairBatch {
 public:
  /// Computes with `path`, which must be available (filter_path_available); AVX2 lists and
  /// computes the pairs four and eight at a time.
  explicit PairBatch(FilterPath path = best_filter_path()) : path_(path) {}

  /// Lists the pairs of the floater at slot `self` (of the records and ids given to
  /// accumulate()) with the slots slots[near[q]] for q < kept, none of them `self`.
  void add(std::uint32_t self, const std::uint32_t* slots, const std::uint32_t* near,
           std::size_t kept);

  /// Pairs listed since the last accumulate().
  std::size_t pairs() const { return pairs_; }

  /// Adds the terms of every pair listed to the sums of both its floaters, sums[slot], for
  /// each floater: its energy, |r|²-weighted energy and force to e, de and (vx, vy, vz), and
  /// (when k.grading > 0) its grading limit into limit, the smaller kept. In a fixed order:
  /// pair by pair as listed, those of the floater listing them first summed on their own.
  /// `records` holds every floater's record by slot (kRecordFields doubles, 64-byte aligned:
  /// x, y, z, σ, σ_max and the unit normal, or 0 when it has none), `ids` its id. Then the
  /// list is empty again.
  void accumulate(bool scaled, const PairConstants& k, const double* records,
                  const std::uint64_t* ids, std::span<PairSums> sums);

  /// The terms of one pair for one of its floaters, as accumulate() keeps them: one cache line.
  struct alignas(64) Terms {
    double e, de, fx, fy, fz, lim, unused[2];
  };

 private:
  FilterPath path_;
  std::size_t pairs_ = 0;
  std::vector<std::uint32_t> i_, j_;  // each pair's slots (the first pairs_ of them)
  std::vector<Terms> terms_;          // per pair: the terms for i, then for j
};

}  // namespace zeroset::detail
