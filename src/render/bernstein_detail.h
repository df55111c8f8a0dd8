#pragma once
// The change to the Bernstein basis, shared by the root finder and the packets of four rays
// in the ray caster, which must round exactly alike.
#include <array>
#include <cstddef>

#include "zeroset/render/roots.h"

namespace zeroset::detail {

/// kInverseBinomials[d][k] = 1 / C(d, k) for d ≤ RootFinder::kMaxDegree (the binomials are
/// exact in double up to that degree).
inline constexpr auto kInverseBinomials = [] {
  constexpr std::size_t n = RootFinder::kMaxDegree + 1;
  std::array<std::array<double, n>, n> binomial{}, inverse{};
  for (std::size_t d = 0; d < n; ++d) {
    binomial[d][0] = binomial[d][d] = 1;
    for (std::size_t k = 1; k < d; ++k)
      binomial[d][k] = binomial[d - 1][k - 1] + binomial[d - 1][k];
    for (std::size_t k = 0; k <= d; ++k) inverse[d][k] = 1 / binomial[d][k];
  }
  return inverse;
}();

}  // namespace zeroset::detail
