#pragma once
/// The "floaters" object of a scene file: the FloaterOptions a scene carries, by field name,
/// read by `zeroset sample` and the viewer and written by the viewer's save-scene.
///
///   "floaters": {"max_count": 2000, "radius": 0, "seed": 1, "seed_count": 200,
///                "cos_weight": true, "clip_projection": true, "snap_to_nodes": true,
///                "scaled_repulsion": true, "radius_grading": 0.1, "radius_adapt": "mixed"}
///
/// Every key is optional; missing ones keep their current value. radius 0 chooses σ̂ from the
/// surface's area.
#include <nlohmann/json.hpp>
#include <string>

#include "zeroset/floaters/floaters.h"

namespace zeroset {

/// Applies `floaters` (the object above) to `options`. Throws BadInput naming `origin` and the
/// JSON pointer of a malformed or out-of-range entry (e.g. "scene.json: /floaters/max_count:
/// expected a whole number from 1 to 100000000"). Unknown keys are an error too, so typos do
/// not pass silently.
void apply_floater_settings(const nlohmann::json& floaters, FloaterOptions& options,
                            const std::string& origin);

/// The "floaters" object for `options`.
nlohmann::json floater_settings_to_json(const FloaterOptions& options);

}  // namespace zeroset
