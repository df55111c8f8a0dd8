// sample_surface, the floater recipe of every front end: settling, the animation of a parameter
// (with a clip that follows it), the step limits, what it measures and says.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <stop_token>
#include <string>
#include <vector>

#include "floater_test_support.h"
#include "support/equation.h"
#include "zeroset/error.h"
#include "zeroset/floaters/sample_surface.h"

namespace zeroset {
namespace {

FloaterOptions few(std::size_t count = 300) {
  FloaterOptions o;
  o.max_count = count;
  o.seed = 5;
  return o;
}

TEST(SampleSurface, SettlesAndMeasuresOnRequest) {
  const Surface s = test::catalog_surface("kummer", {{"mu", 1.5}});
  SampleRun run;
  run.metrics = MetricsOptions{};
  std::vector<double> progress;
  run.on_step = [&](const StepStats&, double f) { progress.push_back(f); };
  const SampleResult r = sample_surface(s, few(), run);
  ASSERT_TRUE(r.system);
  ASSERT_TRUE(r.converged_at);  // the default: until settled
  EXPECT_EQ(r.system->steps_taken(), *r.converged_at);
  EXPECT_EQ(progress.size(), r.system->steps_taken());
  ASSERT_TRUE(r.metrics && r.singular && r.coverage);
  EXPECT_EQ(r.singular->points.size(), 16u);
  EXPECT_LT(r.metrics->residual_median, 1e-3 * s.scene_radius());
  const nlohmann::json j = r.to_json();
  for (const char* key : {"surface", "parameters", "options", "steps", "converged_at_step", "field",
                          "metrics", "singular_set", "singular_coverage"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["options"]["radius"].get<double>(), r.system->nominal_radius());
  EXPECT_FALSE(j.contains("animation"));
}

TEST(SampleSurface, AnimatesFromTheFirstValueWithTheClipFollowing) {
  // The catalog's Kummer clip is a function of mu (a ball of radius max(3, 1.04 (mu - 1))):
  // it must follow the parameter from the start value on.
  const Surface s = test::catalog_surface("kummer");
  SampleRun run;
  run.animation =
      SampleAnimation{.parameter = "mu", .from = 1.2, .to = 4.5, .steps = 20, .settle_steps = 150};
  const SampleResult r = sample_surface(s, few(200), run);
  ASSERT_TRUE(r.animation && r.system);
  EXPECT_LE(r.animation->settle_steps, 150u);
  EXPECT_EQ(r.system->steps_taken(), r.animation->settle_steps + 20);
  EXPECT_DOUBLE_EQ(r.surface.field.parameter_values()[0], 4.5);
  Surface start = s;
  start.field.set_parameter("mu", 1.2);
  start.clip.update(start.field);
  Surface end = s;
  end.field.set_parameter("mu", 4.5);
  end.clip.update(end.field);
  EXPECT_DOUBLE_EQ(start.clip.bounds().hi.x(), 3);
  EXPECT_DOUBLE_EQ(end.clip.bounds().hi.x(), 1.04 * 3.5);
  EXPECT_DOUBLE_EQ(r.surface.clip.bounds().hi.x(), end.clip.bounds().hi.x());
  EXPECT_EQ(r.to_json()["animation"]["steps"], 20);
  run.animation->parameter = "nu";
  EXPECT_THROW(sample_surface(s, few(), run), InvalidArgument);
}

TEST(SampleSurface, FixedStepsAndWarnings) {
  const Surface s = test::equation("x^2", Clip::sphere(1));  // a double plane: ∇F = 0 on it
  SampleRun run;
  run.steps = 4;
  std::vector<std::string> heard;
  run.on_warning = [&](const std::string& line) { heard.push_back(line); };
  const SampleResult r = sample_surface(s, few(), run);
  EXPECT_EQ(r.system->steps_taken(), 4u);
  EXPECT_EQ(heard, r.warnings);
  ASSERT_FALSE(heard.empty());
  EXPECT_NE(heard.back().find("grad F vanishes on a whole sheet"), std::string::npos);
}

TEST(SampleSurface, NoSurfaceNoFloatersAndAStopEndsTheRun) {
  const SampleResult none = sample_surface(test::equation("x - x", Clip::sphere(1)), few());
  EXPECT_FALSE(none.system);
  EXPECT_EQ(none.to_json()["floaters"], 0);
  EXPECT_TRUE(none.to_json()["field"]["vanishes_identically"].get<bool>());
  std::stop_source stop;
  SampleRun run;
  run.on_step = [&](const StepStats&, double) { stop.request_stop(); };
  const SampleResult r =
      sample_surface(test::catalog_surface("cone"), few(), run, stop.get_token());
  EXPECT_TRUE(r.stopped);
  EXPECT_EQ(r.system->steps_taken(), 1u);
}

}  // namespace
}  // namespace zeroset
