// Cancellation of the floaters' set-up work: a viewer job that is cancelled must not sit in
// the area estimate or the singular set search (a clip of many parts makes each point costly).
#include <gtest/gtest.h>

#include <chrono>
#include <stop_token>
#include <string>

#include "floater_test_support.h"
#include "zeroset/floaters/floaters.h"
#include "zeroset/floaters/metrics.h"

namespace zeroset {
namespace {

using Clock = std::chrono::steady_clock;

// Kummer inside the intersection of kMaxClipParts balls (all but one reach past the scene):
// every clip test looks at every part.
Surface heavy_surface() {
  Surface s = test::catalog_surface("kummer", {{"mu", 1.3}});
  Clip clip;
  for (std::size_t k = 0; k < kMaxClipParts; ++k)
    clip.add("sphere:" + std::to_string(3.0 + 1e-3 * static_cast<double>(k)));
  s.clip = clip;
  return s;
}

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

TEST(Cancellation, ReferenceSamplingDrawsNothingOnceStopped) {
  std::stop_source source;
  source.request_stop();
  ReferenceOptions o;
  o.count = 20000;
  o.stop = source.get_token();
  const ReferenceSampling r = reference_sampling(heavy_surface(), o);
  EXPECT_EQ(r.candidates, 0u);
  EXPECT_TRUE(r.points.empty());
  EXPECT_EQ(r.area, 0);
}

TEST(Cancellation, AStoppedFloaterSystemSkipsTheLongSetUp) {
  const Surface s = heavy_surface();
  FloaterOptions o;
  o.threads = 1;
  auto t0 = Clock::now();
  FloaterSystem full(s, o);
  const double full_s = seconds_since(t0);
  ASSERT_GT(full.size(), 0u);

  std::stop_source source;
  source.request_stop();
  t0 = Clock::now();
  FloaterSystem stopped(s, o, source.get_token());
  const double stopped_s = seconds_since(t0);
  // The area estimate alone is 400,000 candidates, each tested against 256 clip parts.
  EXPECT_LT(stopped_s, 0.2 * full_s)
      << "full set-up " << full_s << " s, stopped " << stopped_s << " s";
}

}  // namespace
}  // namespace zeroset
