// The neighbour pass's numerical pieces: the pair terms and their sums (the same bits on every
// path, and the formulas of docs/algorithms.md A.1–A.2 and B.1), the exponential they use, and the
// single-precision prefilter, which must never drop a pair within reach.
#include "pair_kernel_detail.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <random>
#include <vector>

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

// ---- pair sums ----------------------------------------------------------------------------

// Records are 64-byte aligned.
struct AlignedDeleter {
  void operator()(double* p) const { ::operator delete[](p, std::align_val_t{64}); }
};
using Records = std::unique_ptr<double[], AlignedDeleter>;

// Floaters in a small box (most pairs within reach, some beyond), radii 0.05 to 0.2, unit
// normals or none, and some exactly on top of another.
struct Scene {
  std::size_t count;
  Records records;
  std::vector<std::uint64_t> ids;
};

Scene make_scene(std::uint64_t seed, std::size_t count) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), radius(0.05, 0.2);
  Scene scene{count, Records(new (std::align_val_t{64}) double[count * kRecordFields]),
              std::vector<std::uint64_t>(count)};
  for (std::size_t k = 0; k < count; ++k) {
    double* r = scene.records.get() + kRecordFields * k;
    if (k > 0 && k % 7 == 0) {
      std::copy(r - kRecordFields, r - 4, r);  // coincident with the previous floater
    } else {
      r[0] = 0.4 * u(rng);
      r[1] = 0.4 * u(rng);
      r[2] = 0.1 * u(rng);
    }
    r[3] = radius(rng);
    r[4] = 2 * radius(rng);
    if (k % 5 == 3) {
      r[5] = r[6] = r[7] = 0;  // no normal
    } else {
      double n[3] = {u(rng), u(rng), 3 + u(rng)};
      const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (int a = 0; a < 3; ++a) r[5 + a] = n[a] / len;
    }
    scene.ids[k] = 1000 + 3 * k;
  }
  return scene;
}

// Every floater of the scene with its candidates: the floaters after it, in a shuffled order,
// some lists cut short (so lists of every length, and of none, occur). Each pair is listed
// once, by the floater that comes first.
struct Candidates {
  std::vector<std::uint32_t> slots, near;
  std::vector<std::size_t> first, kept;
};

Candidates make_candidates(std::uint64_t seed, std::size_t count) {
  std::mt19937_64 rng(seed);
  Candidates c;
  for (std::uint32_t t = 0; t < count; ++t) c.slots.push_back(t);
  for (std::size_t s = 0; s < count; ++s) {
    std::vector<std::uint32_t> near;
    for (auto t = static_cast<std::uint32_t>(s + 1); t < count; ++t) near.push_back(t);
    std::shuffle(near.begin(), near.end(), rng);
    near.resize(std::min(near.size(), s % 2 == 0 ? near.size() : s / 2));
    c.first.push_back(c.near.size());
    c.kept.push_back(near.size());
    c.near.insert(c.near.end(), near.begin(), near.end());
  }
  return c;
}

constexpr double kOwnLimit = 0.75;

std::vector<PairSums> sums(FilterPath path, bool scaled, const PairConstants& k, const Scene& scene,
                           const Candidates& c) {
  PairBatch batch(path);
  std::vector<PairSums> out(scene.count, PairSums{0, 0, 0, 0, 0, kOwnLimit});
  for (std::size_t s = 0; s < scene.count; ++s) {
    batch.add(static_cast<std::uint32_t>(s), c.slots.data(), c.near.data() + c.first[s], c.kept[s]);
    if (batch.pairs() > 40 || s + 1 == scene.count)
      batch.accumulate(scaled, k, scene.records.get(), scene.ids.data(), out);
  }
  return out;
}

bool same_bits(const PairSums& a, const PairSums& b) { return std::memcmp(&a, &b, sizeof a) == 0; }

TEST(PairBatch, EveryPathGivesTheSameBits) {
  const Scene scene = make_scene(5, 60);
  const Candidates c = make_candidates(6, scene.count);
  for (bool scaled : {true, false})
    for (const PairConstants k : {PairConstants{1.0, 1.0, 0.1}, PairConstants{0.5, 0.0, 0.0},
                                  PairConstants{1.0, 1.0, 0.1, 0.0}}) {
      const auto reference = sums(FilterPath::kScalar, scaled, k, scene, c);
      ASSERT_EQ(reference.size(), scene.count);
      for (FilterPath path : {FilterPath::kSse2, FilterPath::kAvx2}) {
        if (!filter_path_available(path)) continue;
        const auto got = sums(path, scaled, k, scene, c);
        for (std::size_t s = 0; s < scene.count; ++s)
          ASSERT_TRUE(same_bits(got[s], reference[s]))
              << "floater " << s << " path " << static_cast<int>(path) << " scaled " << scaled;
      }
    }
}

// The sums of floater s over every listed pair it is in, from docs/algorithms.md A.1–A.2 and B.1
// written out with std::exp, one way at a time.
PairSums expected(const Scene& scene, const Candidates& c, std::size_t s, bool scaled,
                  const PairConstants& k) {
  std::vector<std::uint32_t> partners;
  for (std::size_t f = 0; f < scene.count; ++f)
    for (std::size_t q = 0; q < c.kept[f]; ++q) {
      const std::uint32_t t = c.slots[c.near[c.first[f] + q]];
      if (f == s) partners.push_back(t);
      if (t == s) partners.push_back(static_cast<std::uint32_t>(f));
    }
  const double* me = scene.records.get() + kRecordFields * s;
  PairSums sum{0, 0, 0, 0, 0, kOwnLimit};
  for (const std::uint32_t t : partners) {
    const double* other = scene.records.get() + kRecordFields * t;
    const double r[3] = {me[0] - other[0], me[1] - other[1], me[2] - other[2]};
    const double d2 = r[0] * r[0] + r[1] * r[1] + r[2] * r[2];
    const double si = me[3], sj = other[3];
    if (!(d2 < 9 * std::max(si * si, sj * sj))) continue;  // beyond reach: nothing
    const bool normals = !(me[5] == 0 && me[6] == 0 && me[7] == 0) &&
                         !(other[5] == 0 && other[6] == 0 && other[7] == 0);
    const double w = k.cos_weight == 0 || !normals
                         ? 1.0
                         : std::abs(me[5] * other[5] + me[6] * other[6] + me[7] * other[7]);
    const double u = d2 / (2 * si * si);
    // The taper (1 − |r|²/9σ²) or, switched off, the plain Gaussian (still cut off at 3σ).
    const auto taper = [&](double factor) { return k.taper > 0 ? factor : 1.0; };
    const double eij = u < 4.5 ? k.alpha * w * std::exp(-u) * taper(1 - u / 4.5) : 0.0;
    double force;
    if (scaled) {
      // P_i = σ_i Σ_j (r_ij/σ_ij) 2E(r_ij; σ_ij) (FloaterOptions::scaled_repulsion).
      const double sij = (si + sj) / 2, x = d2 / (sij * sij);
      force = x < 9 ? 2 * (si / sij) * k.alpha * w * std::exp(-x / 2) * taper(1 - x / 9) : 0.0;
    } else {
      const double x = d2 / (sj * sj);
      const double eji = x < 9 ? k.alpha * w * std::exp(-x / 2) * taper(1 - x / 9) : 0.0;
      force = eij + (si / sj) * (si / sj) * eji;
    }
    sum.e += eij;
    sum.de += d2 * eij;
    sum.vx += force * r[0];
    sum.vy += force * r[1];
    sum.vz += force * r[2];
    if (k.grading > 0) sum.limit = std::min(sum.limit, other[4] + k.grading * std::sqrt(d2));
  }
  return sum;
}

TEST(PairBatch, SumsFollowTheFormulas) {
  Scene scene = make_scene(7, 50);
  // No coincident floaters here (the next test is about those).
  for (std::size_t s = 7; s < scene.count; s += 7) scene.records[kRecordFields * s] += 0.01;
  const Candidates c = make_candidates(8, scene.count);
  for (const PairConstants k : {PairConstants{1.5, 1.0, 0.2}, PairConstants{0.5, 0.0, 0.0},
                                PairConstants{1.5, 1.0, 0.2, 0.0}})
    for (bool scaled : {true, false}) {
      const auto got = sums(best_filter_path(), scaled, k, scene, c);
      for (std::size_t s = 0; s < scene.count; ++s) {
        SCOPED_TRACE(s);
        const PairSums want = expected(scene, c, s, scaled, k);
        const double scale = 1 + std::abs(want.e) + std::abs(want.vx) + std::abs(want.vy);
        EXPECT_NEAR(got[s].e, want.e, 1e-9 * scale);
        EXPECT_NEAR(got[s].de, want.de, 1e-9 * scale);
        EXPECT_NEAR(got[s].vx, want.vx, 1e-9 * scale);
        EXPECT_NEAR(got[s].vy, want.vy, 1e-9 * scale);
        EXPECT_NEAR(got[s].vz, want.vz, 1e-9 * scale);
        EXPECT_DOUBLE_EQ(got[s].limit, want.limit);
      }
    }
}

TEST(PairBatch, CoincidentFloatersArePushedApart) {
  // Two floaters at one point: each feels a finite force, opposite to the other's.
  Scene scene = make_scene(9, 2);
  std::copy(scene.records.get(), scene.records.get() + 3, scene.records.get() + kRecordFields);
  const std::uint32_t slots[2] = {0, 1}, near[1] = {1};
  for (FilterPath path : {FilterPath::kScalar, FilterPath::kAvx2}) {
    if (!filter_path_available(path)) continue;
    PairBatch batch(path);
    batch.add(0, slots, near, 1);
    std::vector<PairSums> s(2, PairSums{0, 0, 0, 0, 0, 1.0});
    batch.accumulate(true, {1.0, 1.0, 0.1}, scene.records.get(), scene.ids.data(), s);
    EXPECT_EQ(batch.pairs(), 0u);
    const double push = std::hypot(s[0].vx, s[0].vy, s[0].vz);
    EXPECT_GT(push, 0);
    EXPECT_TRUE(std::isfinite(push));
    EXPECT_EQ(s[0].vz, 0);
    // Equal radii: the same magnitude, opposite directions.
    const double si = scene.records[3], sj = scene.records[kRecordFields + 3];
    if (si == sj) {
      EXPECT_DOUBLE_EQ(s[0].vx, -s[1].vx);
      EXPECT_DOUBLE_EQ(s[0].vy, -s[1].vy);
    } else {
      EXPECT_LT(s[0].vx * s[1].vx + s[0].vy * s[1].vy, 0);
    }
  }
}

}  // namespace
}  // namespace zeroset::detail
