#include "zeroset/render/roots.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace zeroset {
namespace {

/// Coefficients (ascending) of Π (t - r_i) · scale.
std::vector<double> from_roots(const std::vector<double>& roots, double scale = 1) {
  std::vector<double> c{scale};
  for (double r : roots) {
    std::vector<double> n(c.size() + 1, 0.0);
    for (size_t k = 0; k < c.size(); ++k) {
      n[k + 1] += c[k];
      n[k] -= r * c[k];
    }
    c = n;
  }
  return c;
}

double band_of(const std::vector<double>& c, double t_max) {
  std::vector<double> a(c.size());
  for (size_t k = 0; k < c.size(); ++k) a[k] = std::abs(c[k]);
  return rounding_band(a, t_max);
}

TEST(RootFinder, FindsFirstOfSeveralSimpleRoots) {
  RootFinder f;
  const auto c = from_roots({3.25, 1.5, 7.0, -2.0});
  const auto r = f.first_root(c, 0.0, 10.0, band_of(c, 10));
  ASSERT_TRUE(r);
  EXPECT_NEAR(*r, 1.5, 1e-11);
  const auto r2 = f.first_root(c, 1.6, 10.0, band_of(c, 10));
  ASSERT_TRUE(r2);
  EXPECT_NEAR(*r2, 3.25, 1e-11);
}

TEST(RootFinder, ReportsNothingWithoutRootsInTheInterval) {
  RootFinder f;
  const auto c = from_roots({-1.0, 5.0});
  EXPECT_FALSE(f.first_root(c, 0.0, 4.0, band_of(c, 4)));
  const std::vector<double> positive{1.0, 0.0, 1.0};  // 1 + t^2
  EXPECT_FALSE(f.first_root(positive, -3.0, 3.0, band_of(positive, 3)));
}

TEST(RootFinder, FindsDoubleRootOfTangentRay) {
  RootFinder f;
  // (t - 2)^2 (t - 5): the tangent point comes first and has no sign change.
  const auto c = from_roots({2.0, 2.0, 5.0});
  const auto r = f.first_root(c, 0.0, 8.0, band_of(c, 8));
  ASSERT_TRUE(r);
  EXPECT_NEAR(*r, 2.0, 1e-7);
  EXPECT_EQ(f.stats().band_roots, 1);
}

TEST(RootFinder, FindsDoubleRootsOfSquaredPolynomial) {
  RootFinder f;
  // ((t - 1.3)(t - 2.9))^2 with irrational-ish roots so the coefficients are rounded.
  const double a = 1.0 + std::sqrt(0.1), b = 2.0 + std::sqrt(0.7);
  const auto c = from_roots({a, a, b, b}, 0.37);
  const auto r = f.first_root(c, 0.0, 5.0, band_of(c, 5));
  ASSERT_TRUE(r);
  EXPECT_NEAR(*r, a, 1e-7);
  const auto r2 = f.first_root(c, a + 0.1, 5.0, band_of(c, 5));
  ASSERT_TRUE(r2);
  EXPECT_NEAR(*r2, b, 1e-7);
}

TEST(RootFinder, FindsQuadrupleRoot) {
  RootFinder f;
  const auto c = from_roots({0.7, 0.7, 0.7, 0.7});
  const auto r = f.first_root(c, 0.0, 2.0, band_of(c, 2));
  ASSERT_TRUE(r);
  EXPECT_NEAR(*r, 0.7, 1e-3);
}

TEST(RootFinder, SeparatesCloseSimpleRoots) {
  RootFinder f;
  // Closer roots than this are inside the rounding band: a double root at this precision.
  const auto c = from_roots({1.0 + 1e-4, 1.0 + 3e-4, 4.0});
  const auto r = f.first_root(c, 0.0, 5.0, band_of(c, 5));
  ASSERT_TRUE(r);
  EXPECT_NEAR(*r, 1.0 + 1e-4, 1e-11);
}

// f ≡ 0 on the line (F ≡ 0, or a ray inside a plane): no point is singled out, so no root;
// a constant within the band still counts as a root at the start.
TEST(RootFinder, IdenticallyZeroHasNoFirstRoot) {
  RootFinder f;
  const std::vector<double> zero{0.0, 0.0, 0.0};
  EXPECT_FALSE(f.first_root(zero, 0.5, 2.0, 0.0));
  EXPECT_FALSE(f.first_root(zero, 0.5, 2.0, 1e-9));
  const std::vector<double> tiny{1e-12};
  const auto r = f.first_root(tiny, 0.5, 2.0, 1e-9);
  ASSERT_TRUE(r);
  EXPECT_EQ(*r, 0.5);
}

TEST(RootFinder, FindsRootAtIntervalStart) {
  RootFinder f;
  const auto c = from_roots({1.0, 3.0});
  const auto r = f.first_root(c, 1.0, 2.0, band_of(c, 2));
  ASSERT_TRUE(r);
  EXPECT_NEAR(*r, 1.0, 1e-12);
}

TEST(RootFinder, AgreesWithKnownRootsOfRandomPolynomials) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-4, 4);
  std::uniform_int_distribution<int> deg(1, 12);
  RootFinder f;
  for (int trial = 0; trial < 2000; ++trial) {
    const int d = deg(rng);
    std::vector<double> roots(static_cast<size_t>(d));
    for (double& r : roots) r = u(rng);
    std::sort(roots.begin(), roots.end());
    // Keep roots apart so the expected answer is well conditioned in double precision.
    bool separated = true;
    for (size_t i = 1; i < roots.size(); ++i) separated &= roots[i] - roots[i - 1] > 0.05;
    if (!separated) continue;
    const double t0 = u(rng), t1 = t0 + std::abs(u(rng)) + 0.1;
    const auto c = from_roots(roots, 0.5 + std::abs(u(rng)));
    double expected = NAN;
    for (double r : roots)
      if (r >= t0 && r <= t1) {
        expected = r;
        break;
      }
    const auto got = f.first_root(c, t0, t1, band_of(c, std::max(std::abs(t0), std::abs(t1))));
    if (std::isnan(expected)) {
      EXPECT_FALSE(got) << "trial " << trial;
    } else {
      ASSERT_TRUE(got) << "trial " << trial;
      EXPECT_NEAR(*got, expected, 1e-8) << "trial " << trial << " degree " << d;
    }
  }
}

TEST(RootFinder, FindsTheSameFirstRootWhateverTheGuess) {
  // Guesses before, at, between and beyond the roots, with small and large spreads: the
  // search order changes, the answer must not.
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-4, 4), unit(0, 1);
  std::uniform_int_distribution<int> deg(1, 12);
  RootFinder f;
  int with_root = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const int d = deg(rng);
    std::vector<double> roots(static_cast<size_t>(d));
    for (double& r : roots) r = u(rng);
    std::sort(roots.begin(), roots.end());
    bool separated = true;
    for (size_t i = 1; i < roots.size(); ++i) separated &= roots[i] - roots[i - 1] > 0.05;
    if (!separated) continue;
    const double t0 = u(rng), t1 = t0 + std::abs(u(rng)) + 0.1;
    const auto c = from_roots(roots, 0.5 + std::abs(u(rng)));
    const double band = band_of(c, std::max(std::abs(t0), std::abs(t1)));
    const auto plain = f.first_root(c, t0, t1, band);
    for (int g = 0; g < 4; ++g) {
      RootGuess guess;
      guess.t = t0 + (t1 - t0) * (1.4 * unit(rng) - 0.2);
      guess.spread = (t1 - t0) * std::pow(10.0, -6 * unit(rng));
      const auto guided = f.first_root(c, t0, t1, band, guess);
      ASSERT_EQ(guided.has_value(), plain.has_value()) << "trial " << trial;
      if (plain) {
        EXPECT_NEAR(*guided, *plain, 1e-9) << "trial " << trial << " degree " << d;
      }
    }
    with_root += plain.has_value();
  }
  EXPECT_GT(with_root, 300);
  EXPECT_GT(f.stats().guided_roots, 0);
}

TEST(RootFinder, UsesAGoodGuessToSkipTheSubdivisions) {
  // Roots at 1, 2, 3: without a guess the first is separated from the others by subdivision;
  // a guess next to it finds it in the first piece.
  const auto c = from_roots({1.0, 2.0, 3.0});
  RootFinder plain, guided;
  ASSERT_TRUE(plain.first_root(c, 0.0, 4.0, band_of(c, 4)));
  const auto r = guided.first_root(c, 0.0, 4.0, band_of(c, 4), RootGuess{1.01, 0.05});
  ASSERT_TRUE(r);
  EXPECT_NEAR(*r, 1.0, 1e-12);
  EXPECT_EQ(guided.stats().guided_roots, 1);
  EXPECT_LT(guided.stats().subdivisions, plain.stats().subdivisions);
}

TEST(RootFinder, ReportsTheValueAtTheStartOfTheInterval) {
  RootFinder f;
  const auto c = from_roots({1.0, 3.0}, 2.0);  // 2 (t − 1)(t − 3)
  ASSERT_TRUE(f.first_root(c, 0.5, 4.0, band_of(c, 4)));
  EXPECT_NEAR(f.start_value(), 2 * (0.5 - 1) * (0.5 - 3), 1e-12);
}

}  // namespace
}  // namespace zeroset
