#pragma once
/// The "render" object of a scene file (docs/architecture.md, "Modules"): picture size,
/// anti-aliasing, background, front and back materials and lights, so that a scene reproduces its
/// picture.
///
///   "render": {
///     "size": [800, 800], "samples": 2, "background": "#ffffff",
///     "front": {"diffuse": "#e6a95a", "ambient": 0.12, "specular": 0.35, "shininess": 40},
///     "back":  {"diffuse": [0.06, 0.12, 0.35]},
///     "lights": [{"direction": [0.3, 0.5, 1], "color": [1, 1, 1], "follows_camera": true}]
///   }
///
/// Colours are "#rrggbb" strings (display values, as in image editors) or [r, g, b] arrays of
/// linear values in [0, 1]. Every key is optional; missing ones keep their current value. The
/// command line, scene files and the viewer check these settings with validate_settings below,
/// so each refuses a bad value with the same words.
#include <nlohmann/json_fwd.hpp>
#include <string>

#include "zeroset/render/render.h"

namespace zeroset {

/// Largest picture side, and most pixels of a picture.
inline constexpr int kMaxImageSide = 32768;
inline constexpr double kMaxImagePixels = 100e6;
/// Most anti-aliasing samples along each side of a pixel.
inline constexpr int kMaxSamples = 16;

/// Checks a picture size: sides in [1, kMaxImageSide], at most kMaxImagePixels pixels. Throws
/// SettingError (key "size", value "WxH").
void validate_image_size(long long width, long long height);

/// Checks what a user can set of `options`: the size (validate_image_size), samples in
/// [1, kMaxSamples], colours (linear) in [0, 1], materials (ambient in [0, 1], specular in
/// [0, 10], shininess in [0, 10000]) and lights (finite, non-zero directions). Throws
/// SettingError naming the key as the scene file's "render" object does ("samples",
/// "front/diffuse", "lights/0/direction", ...).
void validate_settings(const RenderOptions& options);

/// Applies `render` (the object above) to `options`, then validates them. Throws BadInput naming
/// `origin` and the JSON pointer of a malformed or out-of-range entry (e.g. "scene.json:
/// /render/front/diffuse: expected '#rrggbb' or [r, g, b]"); nothing is applied then. Unknown keys
/// are an error too, so typos do not pass silently.
void apply_render_settings(const nlohmann::json& render, RenderOptions& options,
                           const std::string& origin);

/// The "render" object for `options` (colours as linear arrays). Camera, threads and the
/// progress callback are not part of it (the camera lives in the scene's "camera").
nlohmann::json render_settings_to_json(const RenderOptions& options);

/// Parses a colour given as "#rrggbb" (display value, gamma 2.2) or "r,g,b" with display
/// values in [0, 1]; returns the linear colour. Throws InvalidArgument naming `what`.
Color parse_display_color(const std::string& text, const std::string& what);

}  // namespace zeroset
