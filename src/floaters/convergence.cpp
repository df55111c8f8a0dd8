// Whether the system has settled, and the residual statistics of a step.
#include "floater_state_detail.h"

#include <numeric>

namespace zeroset::detail {

bool judge_convergence(FloaterState& sys, const StepStats& st) {
  const auto window = static_cast<std::size_t>(sys.opt.converge_window);
  sys.recent.push_back({st.births + st.deaths + st.removed + st.inserted, st.count, st.rms_speed});
  while (sys.recent.size() > window + 1) sys.recent.pop_front();
  if (sys.recent.size() <= window || st.count == 0) return false;
  std::size_t events = 0;
  double speed = 0;
  for (std::size_t k = 1; k < sys.recent.size(); ++k) {
    events += sys.recent[k].events;
    speed += sys.recent[k].speed;
  }
  const double n = static_cast<double>(st.count), w = static_cast<double>(window);
  const double drift = std::abs(n - static_cast<double>(sys.recent.front().count));
  return static_cast<double>(events) <= sys.opt.converge_churn * n * w &&
         drift <= kStationary * n && speed / w < sys.opt.converge_speed;
}

// Median and largest |F|/|∇F| over the floaters not held on nodes (there F and ∇F both vanish
// and the ratio means nothing), from what evaluate_all() counted. The median without sorting
// them all: nonnegative doubles order like their bit patterns, so the histogram of binary
// exponents finds the octave that holds the median, and only that octave is partially
// sorted. Counts and maxima do not depend on which thread saw which floater.
void residual_stats(FloaterState& sys, StepStats& st) {
  std::array<std::size_t, kOctaves> counts{};
  double largest = 0;
  for (std::size_t t = 0; t < sys.octave_counts.size(); ++t) {
    for (std::size_t o = 0; o < kOctaves; ++o) counts[o] += sys.octave_counts[t][o];
    largest = std::max(largest, sys.thread_largest[t]);
  }
  const std::size_t listed = std::accumulate(counts.begin(), counts.end(), std::size_t{0});
  if (listed == 0) return;
  std::size_t rank = listed / 2, o = 0;
  for (; rank >= counts[o]; ++o) rank -= counts[o];
  // The median octave counted again by the next kFineBits bits of the residuals, then the
  // median's fine bin collected and partly sorted (two passes over the residuals take less
  // time than collecting and sorting the whole octave).
  constexpr int kFineBits = 10;
  constexpr int kFineShift = 52 - kFineBits;
  std::array<std::uint32_t, std::size_t{1} << kFineBits> fine{};
  const auto bits = [&](std::size_t i) { return std::bit_cast<std::uint64_t>(sys.residuals[i]); };
  for (std::size_t i = 0; i < floater_count(sys); ++i)
    if ((bits(i) >> 52) == o) ++fine[(bits(i) >> kFineShift) & (fine.size() - 1)];
  std::size_t k = 0;
  for (; rank >= fine[k]; ++k) rank -= fine[k];
  const std::uint64_t bin = (std::uint64_t{o} << kFineBits) | k;
  sys.median_octave.clear();
  for (std::size_t i = 0; i < floater_count(sys); ++i)
    if ((bits(i) >> kFineShift) == bin) sys.median_octave.push_back(sys.residuals[i]);
  const auto mid = sys.median_octave.begin() + static_cast<std::ptrdiff_t>(rank);
  std::nth_element(sys.median_octave.begin(), mid, sys.median_octave.end());
  st.median_residual = *mid;
  st.max_residual = largest;
}

}  // namespace zeroset::detail
