#pragma once
/// Where F is defined over the clip: the one home of two questions every command asks before
/// it trusts its output. Is F undefined (NaN or infinite: a logarithm of a negative number, a
/// square root of one, a pole, an overflow) on part of the clip? Those parts hold no surface,
/// and each stage leaves them out. Does F vanish identically (F ≡ 0, e.g. `0` or `x - x`)?
/// Then every point is on F = 0 and there is no surface to find.
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>

#include "zeroset/surface/surface.h"

namespace zeroset {

/// F on a grid of nodes inside the clip.
struct FieldSurvey {
  long long samples = 0;    ///< grid nodes inside the clip (0: the clip is unbounded)
  long long undefined = 0;  ///< of them, nodes where F is NaN or infinite
  long long zero = 0;       ///< of them, nodes where F = 0 exactly

  /// The fraction of the clip where F is undefined (0 without samples).
  double undefined_fraction() const {
    return samples > 0 ? static_cast<double>(undefined) / static_cast<double>(samples) : 0;
  }
  /// F = 0 at every node: F vanishes identically on the clip.
  bool vanishes_identically() const { return samples > 0 && zero == samples; }
};

/// Nodes of the grid with this many nodes along the longest side of the clip's box.
inline constexpr int kSurveyNodes = 40;

/// Samples F at the nodes of a grid of `nodes` (≥ 2) along the longest side of the clip's
/// bounding box that lie inside the clip (the box's centre too, so that a tiny clip has one).
/// An unbounded clip gives an empty survey. About nodes³/2 evaluations of F (milliseconds).
/// Throws InvalidArgument for nodes < 2.
FieldSurvey survey_field(const Surface& surface, int nodes = kSurveyNodes);

/// The warning a command gives for a survey, or none: that F vanishes identically ("there is
/// no surface"), or on which fraction of the clip F is undefined ("those parts are left out").
std::optional<std::string> survey_warning(const Surface& surface, const FieldSurvey& survey);

/// The survey in a stats file: {"samples", "undefined_samples", "undefined_fraction",
/// "vanishes_identically"}.
nlohmann::json survey_json(const FieldSurvey& survey);

}  // namespace zeroset
