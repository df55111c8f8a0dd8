#pragma once
/// The limits of a surface's own settings (its camera), checked the same way by the command
/// line, scene files and the viewer.
#include "zeroset/surface/surface.h"

namespace zeroset {

/// The field of view a camera may have, in degrees.
inline constexpr double kMinFovDeg = 1;
inline constexpr double kMaxFovDeg = 170;

/// The one check of a Camera: azimuth, roll and target finite, elevation in [-90, 90] degrees,
/// distance finite and ≥ 0 (0: fit the clip), fov_deg in [kMinFovDeg, kMaxFovDeg]. Throws
/// SettingError naming the field (azimuth_deg, elevation_deg, distance, fov_deg, target, roll_deg) as
/// scene files do.
void validate_camera(const Camera& camera);

}  // namespace zeroset
