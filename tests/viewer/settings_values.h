#pragma once
// Values other than the defaults for every key of the scene file's "floaters" and "mesh"
// objects, as the viewer's `set` command takes them: the tests that switch every setting.
#include <map>
#include <nlohmann/json.hpp>
#include <string>

namespace zeroset::viewer::test {

// A value other than the default for every key, as `set` takes it. A key of the scene objects
// missing here fails the tests, so a new setting cannot go untested.
inline const std::map<std::string, std::string> kFloaterValues = {{"max_count", "700"},
                                                                  {"seed_count", "50"},
                                                                  {"seed", "7"},
                                                                  {"radius", "0.2"},
                                                                  {"radius_grading", "0"},
                                                                  {"feedback", "5"},
                                                                  {"equilibrium_speed", "2"},
                                                                  {"estimator_interval", "3"},
                                                                  {"cos_weight", "off"},
                                                                  {"clip_projection", "off"},
                                                                  {"snap_to_nodes", "off"},
                                                                  {"scaled_repulsion", "off"},
                                                                  {"radius_adapt", "wh"},
                                                                  {"clip_newton", "off"},
                                                                  {"average_radius_factor", "off"},
                                                                  {"local_nominal_radius", "off"},
                                                                  {"energy_taper", "off"},
                                                                  {"fission_offset", "off"}};
inline const std::map<std::string, std::string> kMeshValues = {{"cells", "28"},
                                                               {"improve", "5"},
                                                               {"boundary", "fix"},
                                                               {"grid", "sparse"},
                                                               {"refine_steps", "0"},
                                                               {"curvature", "off"},
                                                               {"curvature_weight", "40"},
                                                               {"singularity", "off"},
                                                               {"flips", "off"},
                                                               {"find_singular", "off"},
                                                               {"crossings", "off"},
                                                               {"curves", "off"},
                                                               {"improver", "paper"}};

// The scene file's value for a `set` value: on/off become true/false, numbers stay numbers.
inline nlohmann::json expected_value(const std::string& text) {
  if (text == "off") return false;
  if (text == "on") return true;
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
  return j.is_discarded() ? nlohmann::json(text) : j;
}

}  // namespace zeroset::viewer::test
