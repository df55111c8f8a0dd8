#pragma once
// Pieces of the floaters' neighbour (repulsion) pass that are worth testing on their own: an
// exponential for the pair terms, written so the compiler vectorises loops that call it, and
// the single-precision prefilter threshold that never drops a pair within the cutoff.
// Private to the floaters module.
#include <bit>
#include <cstdint>
#include <numbers>

namespace zeroset::detail {

/// e^a for a in [−4.5, 0], the range of every pair term inside the cutoff (|r| < 3σ gives
/// exponents above −9/2), with relative error below 1e-10: Cody–Waite reduction to
/// |r| ≤ ln2/2 and a degree-7 polynomial fitted at Chebyshev nodes (error 5.5e-11 on that
/// interval). The pair energies need far less; std::exp is exact to the last bit, but a call per
/// pair cannot be vectorised and cost a sixth of a step. Arguments below −64 are taken as −64
/// (those terms lie beyond the cutoff and are discarded); a NaN gives an unspecified value.
/// Branch-free and pure, so loops calling it vectorise.
inline double exp_cutoff(double a) {
  a = a < -64.0 ? -64.0 : a;
  // Adding 1.5·2^52 rounds a·log2(e) to the nearest integer k, which then sits in the low bits
  // of t; k << 52 added to the bits of p multiplies p by 2^k (k ≥ −93: no underflow).
  constexpr double kShift = 0x1.8p52;
  constexpr double kLn2Hi = 0x1.62e42feep-1;  // trailing zeros: k·kLn2Hi is exact
  constexpr double kLn2Lo = 0x1.a39ef35793c76p-33;
  const double t = a * std::numbers::log2e + kShift;
  const double k = t - kShift;
  const double r = (a - k * kLn2Hi) - k * kLn2Lo;
  double p = 0x1.a17df2ec2bc60p-13;
  p = p * r + 0x1.6da753185ad01p-10;
  p = p * r + 0x1.1110a6222ea35p-7;
  p = p * r + 0x1.555464a0f079ep-5;
  p = p * r + 0x1.5555557e7125ep-3;
  p = p * r + 0x1.0000005c89e4ep-1;
  p = p * r + 0x1.fffffffff61fdp-1;
  p = p * r + 0x1.ffffffffa7135p-1;
  const std::uint64_t scale = std::bit_cast<std::uint64_t>(t) << 52;
  return std::bit_cast<double>(std::bit_cast<std::uint64_t>(p) + scale);
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

}  // namespace zeroset::detail
