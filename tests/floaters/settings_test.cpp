// The "floaters" object of scene files: every key applied, written back unchanged, and each
// malformed entry refused with its JSON pointer.
#include "zeroset/floaters/settings.h"

#include <gtest/gtest.h>

#include "zeroset/error.h"

namespace zeroset {
namespace {

using nlohmann::json;

TEST(FloaterSettings, EveryKeyIsAppliedAndWrittenBack) {
  const json j = json::parse(R"({"max_count": 500, "seed_count": 50, "seed": 9,
      "radius": 0.25, "radius_grading": 0.3, "cos_weight": false, "clip_projection": false,
      "snap_to_nodes": false, "scaled_repulsion": false, "radius_adapt": "curvature",
      "feedback": 7.5, "equilibrium_speed": 2, "estimator_interval": 3})");
  FloaterOptions o;
  apply_floater_settings(j, o, "s.json");
  EXPECT_EQ(o.max_count, 500u);
  EXPECT_EQ(o.seed_count, 50u);
  EXPECT_EQ(o.seed, 9u);
  EXPECT_EQ(o.radius, 0.25);
  EXPECT_EQ(o.radius_grading, 0.3);
  EXPECT_FALSE(o.cos_weight);
  EXPECT_FALSE(o.clip_projection);
  EXPECT_FALSE(o.snap_to_nodes);
  EXPECT_FALSE(o.scaled_repulsion);
  EXPECT_EQ(o.radius_adapt, RadiusAdapt::kCurvature);
  EXPECT_EQ(o.feedback, 7.5);
  EXPECT_EQ(o.equilibrium_speed, 2);
  EXPECT_EQ(o.estimator_interval, 3);
  EXPECT_EQ(floater_settings_to_json(o), j);
  // Missing keys keep their value.
  FloaterOptions kept = o;
  apply_floater_settings(json::object(), kept, "s.json");
  EXPECT_EQ(floater_settings_to_json(kept), j);
}

TEST(FloaterSettings, MalformedEntriesAreRefusedWithTheirPointer) {
  const std::pair<const char*, const char*> cases[] = {
      {R"({"max_count": -5})", "/floaters/max_count"},
      {R"({"max_count": 300.5})", "/floaters/max_count"},
      {R"({"max_count": 1e30})", "/floaters/max_count"},
      {R"({"max_count": "many"})", "/floaters/max_count"},
      {R"({"seed": -1})", "/floaters/seed"},
      {R"({"max_count": 500, "seed": -1})", "/floaters/seed"},
      {R"({"seed_count": -3})", "/floaters/seed_count"},
      {R"({"radius": -1})", "/floaters/radius"},
      {R"({"radius_grading": "a"})", "/floaters/radius_grading"},
      {R"({"cos_weight": 1})", "/floaters/cos_weight"},
      {R"({"radius_adapt": "fast"})", "/floaters/radius_adapt"},
      {R"({"feedback": -1})", "/floaters/feedback: must lie in [0, 1000]"},
      {R"({"feedback": 1001})", "/floaters/feedback: must lie in [0, 1000]"},
      {R"({"feedback": "strong"})", "/floaters/feedback: expected a number"},
      {R"({"equilibrium_speed": -0.1})", "/floaters/equilibrium_speed: must lie in [0, 1000]"},
      {R"({"estimator_interval": 0})", "/floaters/estimator_interval: must lie in [1, 100000]"},
      {R"({"estimator_interval": 1e12})", "/floaters/estimator_interval: must lie in [1, 100000]"},
      {R"({"estimator_interval": 2.5})", "/floaters/estimator_interval: expected a whole"},
      {R"({"max_cuont": 5})", "/floaters/max_cuont: unknown key"},
      {R"([2])", "/floaters: expected an object"},
  };
  for (const auto& [text, where] : cases) {
    FloaterOptions o;
    const FloaterOptions before = o;
    try {
      apply_floater_settings(json::parse(text), o, "s.json");
      ADD_FAILURE() << text;
    } catch (const BadInput& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("s.json: ") + where), std::string::npos)
          << text << ": " << e.what();
    }
    // Nothing is applied from an object with a bad entry.
    EXPECT_EQ(floater_settings_to_json(o), floater_settings_to_json(before)) << text;
  }
}

}  // namespace
}  // namespace zeroset
