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
  check(std::isfinite(c.azimuth_deg), "azimuth_deg", c.azimuth_deg, "must be finite");
  check(std::abs(c.elevation_deg) <= 90, "elevation_deg", c.elevation_deg,
        "must lie in [-90, 90] degrees");
  check(std::isfinite(c.distance) && c.distance >= 0, "distance", c.distance,
        "must be finite and ≥ 0 (0: fit the clip volume)");
  check(c.fov_deg >= kMinFovDeg && c.fov_deg <= kMaxFovDeg, "fov_deg", c.fov_deg,
        fmt::format("must lie in [{}, {}] degrees", kMinFovDeg, kMaxFovDeg));
  check(std::isfinite(c.roll_deg), "roll_deg", c.roll_deg, "must be finite");
  for (int a = 0; a < 3; ++a)
    check(std::isfinite(c.target[a]), "target", c.target[a], "must be finite");
}

}  // namespace zeroset
