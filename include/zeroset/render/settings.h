#pragma once
/// The "render" object of a scene file (DESIGN §2): picture size, anti-aliasing, background,
/// front and back materials and lights, so that a scene reproduces its picture.
///
///   "render": {
///     "size": [800, 800], "samples": 2, "background": "#ffffff",
///     "front": {"diffuse": "#e6a95a", "ambient": 0.12, "specular": 0.35, "shininess": 40},
///     "back":  {"diffuse": [0.06, 0.12, 0.35]},
///     "lights": [{"direction": [0.3, 0.5, 1], "color": [1, 1, 1], "follows_camera": true}]
///   }
///
/// Colours are "#rrggbb" strings (display values, as in image editors) or [r, g, b] arrays of
/// linear values in [0, 1]. Every key is optional; missing ones keep their current value.
#include <nlohmann/json.hpp>
#include <string>

#include "zeroset/render/render.h"

namespace zeroset {

/// Applies `render` (the object above) to `options`. Throws BadInput naming `origin` and the
/// JSON pointer of a malformed or out-of-range entry (e.g. "scene.json: /render/front/diffuse:
/// expected '#rrggbb' or [r, g, b]"). Unknown keys are an error too, so typos do not pass
/// silently.
void apply_render_settings(const nlohmann::json& render, RenderOptions& options,
                           const std::string& origin);

/// The "render" object for `options` (colours as linear arrays). Camera, threads and the
/// progress callback are not part of it (the camera lives in the scene's "camera").
nlohmann::json render_settings_to_json(const RenderOptions& options);

/// Parses a colour given as "#rrggbb" (display value, gamma 2.2) or "r,g,b" with display
/// values in [0, 1]; returns the linear colour. Throws InvalidArgument naming `what`.
Color parse_display_color(const std::string& text, const std::string& what);

}  // namespace zeroset
