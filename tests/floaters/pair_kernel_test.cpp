// The neighbour pass's numerical pieces: the exponential of the pair terms and the
// single-precision prefilter, which must never drop a pair within reach.
#include "pair_kernel_detail.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace zeroset::detail {
namespace {

TEST(ExpCutoff, MatchesStdExpOverTheCutoffRange) {
  double worst = 0;
  for (int k = 0; k <= 1'000'000; ++k) {
    const double a = -4.5 * k / 1e6;
    worst = std::max(worst, std::abs(exp_cutoff(a) / std::exp(a) - 1));
  }
  EXPECT_LT(worst, 1e-10);
  EXPECT_GT(worst, 0);  // it is an approximation: the bound above is what is claimed
}

TEST(ExpCutoff, StaysFiniteAndPositiveFarBeyondTheCutoff) {
  for (double a : {-10.0, -64.0, -100.0, -1e6, -1e300}) {
    SCOPED_TRACE(a);
    const double e = exp_cutoff(a);
    EXPECT_TRUE(std::isfinite(e));
    EXPECT_GT(e, 0);
    EXPECT_LE(e, 1.1 * std::exp(-std::min(-a, 64.0)));
  }
}

// The prefilter's arithmetic: coordinates rounded to float, squared distance summed in float.
float float_distance2(const double* p, const double* q) {
  float d2[3];
  for (int k = 0; k < 3; ++k) {
    const float d = static_cast<float>(p[k]) - static_cast<float>(q[k]);
    d2[k] = d * d;
  }
  return (d2[0] + d2[1]) + d2[2];
}

TEST(PrefilterThreshold, KeepsEveryPairWithinReach) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> coordinate(-1, 1), unit(0, 1);
  for (int k = 0; k < 1'000'000; ++k) {
    // Reaches from 2^-30 to 1, pairs just inside them, anywhere in the unit cube.
    const double reach = std::ldexp(1.0 + unit(rng), -static_cast<int>(30 * unit(rng)) - 1);
    double p[3], q[3], dir[3], norm = 0;
    for (int a = 0; a < 3; ++a) {
      dir[a] = coordinate(rng);
      norm += dir[a] * dir[a];
    }
    norm = std::sqrt(norm);
    const double d = reach * (1 - 1e-12 * unit(rng));
    for (int a = 0; a < 3; ++a) {
      p[a] = coordinate(rng) * (1 - reach);
      q[a] = p[a] + d * dir[a] / norm;
    }
    double exact = 0;
    for (int a = 0; a < 3; ++a) exact += (p[a] - q[a]) * (p[a] - q[a]);
    if (!(exact < reach * reach)) continue;
    ASSERT_LT(float_distance2(p, q), prefilter_threshold(reach)) << "reach " << reach;
  }
}

TEST(PrefilterThreshold, KeepsLittleBeyondReach) {
  // It widens the reach by rounding margins only: pairs at 1.01 × reach are dropped.
  for (double reach : {1e-3, 1e-2, 0.1, 0.5}) {
    const double p[3] = {0.25, -0.5, 0.125}, q[3] = {0.25 + 1.01 * reach, -0.5, 0.125};
    EXPECT_GE(float_distance2(p, q), prefilter_threshold(reach)) << "reach " << reach;
  }
}

}  // namespace
}  // namespace zeroset::detail
