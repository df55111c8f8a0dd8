#pragma once
/// Keyframed animation (docs/rendering.md, "Keyframes"): parameter values and camera settings
/// given at moments of an animation, eased in between. The scene file's
/// "animation": {"keyframes": [...]} holds them; `zeroset animate` renders them and
/// `zeroset export --animate` writes them for POV-Ray.
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "zeroset/surface/surface.h"

namespace zeroset {

/// How a value moves from one keyframe to the next: s ∈ [0, 1] (the share of the segment's
/// time gone) becomes the share of the way done. Each is monotone from 0 to 1, so values stay
/// between those of the keyframes.
enum class Ease {
  kLinear,  ///< s
  kIn,      ///< s²: starts slowly
  kOut,     ///< 1 − (1 − s)²: ends slowly
  kInOut,   ///< smoothstep 3s² − 2s³: starts and ends slowly (the default)
};

/// The ease function's value at s ∈ [0, 1].
double ease(Ease e, double s);
/// The name in scene files: "linear", "in", "out", "in-out".
const char* ease_name(Ease e);
/// The ease of that name (as ease_name gives it), or nullopt.
std::optional<Ease> find_ease(std::string_view name);

/// One animated value: a parameter's, or a camera field's (`azimuth_deg`, `elevation_deg`,
/// `distance`, `roll_deg`, `fov_deg`, `ortho_height`). Held at the first key's value before it and
/// at the last key's after it; between two keys it follows the first one's ease.
struct KeyTrack {
  std::string name;
  std::vector<double> times;  ///< animation time in [0, 1], strictly increasing
  std::vector<double> values;
  std::vector<Ease> eases;  ///< eases[i]: from key i to key i + 1

  double value(double time) const;
};

/// The tracks of an animation. Time runs from 0 (the first frame) to 1 (the last): frame f of
/// an N-frame animation is at f / (N − 1).
struct Keyframes {
  std::vector<KeyTrack> params;  ///< one per animated parameter
  std::vector<KeyTrack> camera;  ///< one per animated camera field
  /// The camera's projection switched at keyframes: (time, projection) in increasing time. A
  /// frame has the projection of the last switch at or before its time (the first one's
  /// before it); empty: the surface's own throughout.
  std::vector<std::pair<double, Projection>> projections;

  bool empty() const { return params.empty() && camera.empty() && projections.empty(); }
  const KeyTrack* param(const std::string& name) const;
  /// `surface` at `time`: its parameters and camera with every track's value there.
  Surface at(Surface surface, double time) const;
};

/// The time of frame f of an N-frame animation: f / (N − 1), and 0 for a single frame.
double frame_time(int frame, int frames);

/// The camera fields a keyframe may set.
const std::vector<std::string>& keyframe_camera_fields();

/// Reads `settings`' "animation"/"keyframes" (none: empty Keyframes) for `surface`: a list of
/// {"time": T in [0, 1] | "frame": F in [0, frames − 1], "params": {NAME: value, ...},
/// "camera": {FIELD: value, ..., "projection": "perspective" | "orthographic"}, "ease":
/// "linear" | "in" | "out" | "in-out"}, in increasing time. Throws BadInput "ORIGIN:
/// /animation/keyframes/i/...: what is wrong" for an unknown key, parameter or ease, a time out of
/// order, or a camera validate_camera refuses (a keyframe's distance must be positive).
Keyframes read_keyframes(const nlohmann::json& settings, const Surface& surface, int frames,
                         const std::string& origin);

}  // namespace zeroset
