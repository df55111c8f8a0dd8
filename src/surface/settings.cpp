#include "zeroset/surface/settings.h"

#include <fmt/core.h>

#include <cmath>
#include <cstdlib>
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
  check(c.ortho_height >= 0 && c.ortho_height <= kMaxCameraLength, "ortho_height", c.ortho_height,
        fmt::format("must lie in [0, {:g}] (0: fit the clip volume)", kMaxCameraLength));
  for (int a = 0; a < 3; ++a)
    check(std::abs(c.target[a]) <= kMaxCameraLength, "target", c.target[a], length);
}

const char* projection_name(Projection p) {
  return p == Projection::orthographic ? "orthographic" : "perspective";
}

std::optional<Projection> find_projection(std::string_view name) {
  if (name == "perspective" || name == "persp") return Projection::perspective;
  if (name == "orthographic" || name == "ortho") return Projection::orthographic;
  return std::nullopt;
}

Camera with_projection(Camera camera, std::string_view spec, const std::string& what) {
  const size_t colon = spec.find(':');
  const std::optional<Projection> p = find_projection(spec.substr(0, colon));
  const std::string text(spec);
  const char* expected = "expected perspective, ortho or ortho:HEIGHT (HEIGHT > 0, world units)";
  if (!p) throw InvalidArgument(what, text, expected);
  camera.projection = *p;
  camera.ortho_height = 0;  // fit the clip volume
  if (colon == std::string_view::npos) return camera;
  if (*p != Projection::orthographic)
    throw InvalidArgument(what, text, "only an orthographic camera takes a HEIGHT");
  const std::string height(spec.substr(colon + 1));
  char* end = nullptr;
  const double h = std::strtod(height.c_str(), &end);
  if (height.empty() || end != height.c_str() + height.size() || !(h > 0) ||
      !(h <= kMaxCameraLength))
    throw InvalidArgument(what, text,
                          fmt::format("{}; HEIGHT at most {:g}", expected, kMaxCameraLength));
  camera.ortho_height = h;
  return camera;
}

}  // namespace zeroset
