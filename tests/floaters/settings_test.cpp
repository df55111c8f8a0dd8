// The "floaters" object of scene files: every key applied, written back unchanged, and each
// malformed entry refused with its JSON pointer.
#include "zeroset/floaters/settings.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "zeroset/error.h"

namespace zeroset {
namespace {

using nlohmann::json;

TEST(FloaterSettings, EveryKeyIsAppliedAndWrittenBack) {
  const json j = json::parse(R"({"max_count": 500, "seed_count": 50, "seed": 9,
      "radius": 0.25, "radius_grading": 0.3, "cos_weight": false, "clip_projection": false,
      "snap_to_nodes": false, "scaled_repulsion": false, "radius_adapt": "curvature",
      "feedback": 30, "equilibrium_speed": 2.5, "estimator_interval": 3, "clip_newton": false,
      "average_radius_factor": false, "local_nominal_radius": false, "energy_taper": false,
      "fission_offset": false})");
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
  EXPECT_EQ(o.feedback, 30);
  EXPECT_EQ(o.equilibrium_speed, 2.5);
  EXPECT_EQ(o.estimator_interval, 3);
  EXPECT_FALSE(o.clip_newton);
  EXPECT_FALSE(o.average_radius_factor);
  EXPECT_FALSE(o.local_nominal_radius);
  EXPECT_FALSE(o.energy_taper);
  EXPECT_FALSE(o.fission_offset);
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
      {R"({"feedback": -1})", "/floaters/feedback"},
      {R"({"feedback": 70})", "/floaters/feedback: must lie in [0, 66.6667)"},
      {R"({"feedback": "strong"})", "/floaters/feedback"},
      {R"({"equilibrium_speed": 0})", "/floaters/equilibrium_speed"},
      {R"({"equilibrium_speed": 17})", "/floaters/equilibrium_speed"},
      {R"({"estimator_interval": 0})", "/floaters/estimator_interval"},
      {R"({"estimator_interval": 1001})", "/floaters/estimator_interval"},
      {R"({"estimator_interval": 2.5})", "/floaters/estimator_interval"},
      {R"({"clip_newton": "no"})", "/floaters/clip_newton"},
      {R"({"average_radius_factor": 0})", "/floaters/average_radius_factor"},
      {R"({"local_nominal_radius": null})", "/floaters/local_nominal_radius"},
      {R"({"energy_taper": []})", "/floaters/energy_taper"},
      {R"({"fission_offset": 1})", "/floaters/fission_offset"},
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

// A front end's options (flags, keywords) go through the scene file's reader as the same keys,
// refused with the key's name and the scene file's words, all or nothing.
TEST(FloaterSettings, GivenOptionsGoThroughTheOneReaderAndNameTheirKey) {
  FloaterOptions o;
  apply_floater_options({{"max_count", 500}, {"cos_weight", false}, {"radius_adapt", "wh"}}, o);
  EXPECT_EQ(o.max_count, 500u);
  EXPECT_FALSE(o.cos_weight);
  EXPECT_EQ(o.radius_adapt, RadiusAdapt::kWitkinHeckbert);
  const json cases[] = {{{"max_count", 0}},       {{"max_count", -3}},
                        {{"cos_weight", "yes"}},  {{"radius_adapt", "fast"}},
                        {{"feedback", "strong"}}, {{"radius", -1}},
                        {{"seed", 0.5}},          {{"max_cuont", 3}}};
  for (const json& given : cases) {
    FloaterOptions kept;
    kept.max_count = 77;
    const std::string key = given.begin().key();
    try {
      apply_floater_options(given, kept);
      ADD_FAILURE() << given.dump() << " was taken";
    } catch (const SettingError& e) {
      EXPECT_EQ(e.key(), key) << given.dump();
      // The scene file says the same about the same entry.
      FloaterOptions scene;
      try {
        apply_floater_settings(given, scene, "s.json");
        ADD_FAILURE() << given.dump();
      } catch (const BadInput& b) {
        EXPECT_EQ(std::string(b.what()), "s.json: /floaters/" + key + ": " + e.why());
      }
    }
    EXPECT_EQ(kept.max_count, 77u) << "all or nothing: " << given.dump();
  }
}

}  // namespace
}  // namespace zeroset
