#pragma once
/// SURFER's .jsurf files (docs/scenes.md, "SURFER files"): a Java properties file with the
/// equation, the parameters a..d, the clip sphere (scale_factor), the rotation, the camera,
/// colours and lights. Read into a Scene, whose "render" object carries the colours and
/// lights; written from a Scene whose "render" object is in render_settings_to_json's form.
#include <string>
#include <string_view>

#include "zeroset/surface/scene.h"

namespace zeroset {

/// SURFER names its parameters a, b, c, d: at most this many.
inline constexpr int kMaxJsurfParameters = 4;

/// Reads .jsurf text. `origin` names it in messages ("kummer.jsurf:12: ..."). Throws BadInput
/// naming the line for a malformed line or escape, a missing surface_equation, a number that
/// does not parse or lies out of range, a transform that is not a rotation with a uniform
/// scale, or an orthographic camera (zeroset has a perspective camera only).
Scene jsurf_to_scene(std::string_view text, const std::string& origin);
/// Reads a .jsurf file (IoError when it cannot be read).
Scene read_jsurf(const std::string& path);

/// The .jsurf text of `scene`: its parameters renamed to a..d where they have other names,
/// scale_factor from the clip sphere, rotation_matrix and camera_transform from the camera,
/// colours and lights from scene.settings["render"] (linear colours as arrays; lights that do
/// not follow the camera are turned into the camera's frame). Throws BadInput when SURFER cannot
/// show the surface: more than kMaxJsurfParameters parameters, a field that is not a
/// polynomial in x, y, z, an equation that needs more than SURFER's syntax, or a clip that is
/// not one sphere about the origin.
std::string scene_to_jsurf(const Scene& scene);
/// Writes scene_to_jsurf atomically.
void write_jsurf(const Scene& scene, const std::string& path);

}  // namespace zeroset
