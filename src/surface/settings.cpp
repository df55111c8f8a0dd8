#include "zeroset/surface/settings.h"

#include <fmt/core.h>

#include <cmath>
#include <string>

#include "zeroset/error.h"

namespace zeroset {

void validate_camera(const Camera& c) {
  auto check = [](bool ok, const char* key, double value, const std::string& why) {
    if (!ok) throw SettingError(key, fmt::format("{}", value), why);
  };
  const std::string angle =
      fmt::format("must lie in [-{:g}, {:g}] degrees", kMaxCameraAngleDeg, kMaxCameraAngleDeg);
  const std::string length =
      fmt::format("must lie in [-{:g}, {:g}]", kMaxCameraLength, kMaxCameraLength);
  check(std::abs(c.azimuth_deg) <= kMaxCameraAngleDeg, "azimuth_deg", c.azimuth_deg, angle);
  check(std::abs(c.elevation_deg) <= 90, "elevation_deg", c.elevation_deg,
        "must lie in [-90, 90] degrees");
  check(c.distance >= 0 && c.distance <= kMaxCameraLength, "distance", c.distance,
        fmt::format("must lie in [0, {:g}] (0: fit the clip volume)", kMaxCameraLength));
  check(c.fov_deg >= kMinFovDeg && c.fov_deg <= kMaxFovDeg, "fov_deg", c.fov_deg,
        fmt::format("must lie in [{}, {}] degrees", kMinFovDeg, kMaxFovDeg));
  check(std::abs(c.roll_deg) <= kMaxCameraAngleDeg, "roll_deg", c.roll_deg, angle);
  for (int a = 0; a < 3; ++a)
    check(std::abs(c.target[a]) <= kMaxCameraLength, "target", c.target[a], length);
}

}  // namespace zeroset
