#pragma once
/// The limits of a surface's own settings (its camera), checked the same way by the command
/// line, scene files and the viewer.
#include <optional>
#include <string_view>

#include "zeroset/surface/surface.h"

namespace zeroset {

/// The field of view a camera may have, in degrees.
inline constexpr double kMinFovDeg = 1;
inline constexpr double kMaxFovDeg = 170;

/// The largest magnitude of an angle (azimuth, roll) in degrees: any turn is reached well
/// within it, and cos and sin still tell its degrees apart.
inline constexpr double kMaxCameraAngleDeg = 1e6;
/// The largest camera distance and target coordinate: far beyond the clip volumes
/// (kMaxClipCoordinate), yet squared distances between them stay finite.
inline constexpr double kMaxCameraLength = 1e12;

/// The one check of a Camera: azimuth and roll within ±kMaxCameraAngleDeg, elevation in
/// [-90, 90] degrees, distance in [0, kMaxCameraLength] (0: fit the clip), target coordinates
/// within ±kMaxCameraLength, fov_deg in [kMinFovDeg, kMaxFovDeg], ortho_height in
/// [0, kMaxCameraLength] (0: fit the clip). Throws SettingError naming the field
/// (azimuth_deg, elevation_deg, distance, fov_deg, target, roll_deg, ortho_height) as scene
/// files do.
void validate_camera(const Camera& camera);

/// A projection's name in scene files and on the command line: "perspective" or
/// "orthographic"; find_projection also takes "ortho" and "persp". nullopt for other names.
const char* projection_name(Projection p);
std::optional<Projection> find_projection(std::string_view name);
/// `camera` with a projection given as text, as `--projection` and Python's `projection=`
/// take it: "perspective", or "ortho[:HEIGHT]" ("orthographic[:HEIGHT]"), HEIGHT > 0 in world
/// units, without it the window fits the clip volume. Throws InvalidArgument naming `what`
/// (the flag or keyword) for anything else.
Camera with_projection(Camera camera, std::string_view spec, const std::string& what);

}  // namespace zeroset
