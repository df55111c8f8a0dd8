#pragma once
// Counter-based random numbers: a stream is a pure function of (seed, floater id, step,
// purpose), so results do not depend on the order in which threads draw them.
#include <cmath>
#include <cstdint>

namespace zeroset::detail {

/// SplitMix64's finaliser: a bijective 64-bit mix with good avalanche.
inline std::uint64_t mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// What a stream is used for, so streams of one floater in one step never coincide.
enum class Stream : std::uint64_t {
  kInsert = 1,
  kFission = 2,
  kDeath = 3,
  kCurvature = 4,
  kReference = 5,
};

class Rng {
 public:
  Rng(std::uint64_t seed, std::uint64_t id, std::uint64_t step, Stream stream)
      : state_(mix64(mix64(mix64(seed) ^ id) ^ step) ^ static_cast<std::uint64_t>(stream)) {}

  std::uint64_t next() {
    state_ += 0x9e3779b97f4a7c15ULL;
    std::uint64_t z = state_;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Uniform in [a, b).
  double uniform(double a, double b) { return a + (b - a) * uniform(); }

 private:
  std::uint64_t state_;
};

}  // namespace zeroset::detail
