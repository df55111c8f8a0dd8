#pragma once
/// The singular set S = {F = 0, ∇F = 0} of a surface inside its clip, found numerically:
/// isolated singular points (nodes, cusps), singular curves traced as polylines and classified
/// by the Hessian across them, and the special points where curves change (pinch points,
/// triple points, ends on the clip). See docs/singular.md for the method and its limits.
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <stop_token>
#include <string>
#include <string_view>
#include <vector>

#include "zeroset/surface/singular_kinds.h"
#include "zeroset/surface/surface.h"
#include "zeroset/types.h"

namespace zeroset {

/// One traced curve of S: a polyline whose vertices satisfy F = 0 and ∇F = 0 to about 1e-12 of
/// the scene radius. A curve has one kind; it is split where the kind changes (at pinch points).
struct SingularCurve {
  CurveKind kind = CurveKind::kCrossing;
  std::vector<Vec3> points;  ///< at least two; the last equals the first when closed
  bool closed = false;
  double length() const;
};

/// A special point of S.
struct SingularPoint {
  Vec3 position = Vec3::Zero();
  SingularPointKind kind = SingularPointKind::kNode;
};

/// The singular set as found.
struct SingularSet {
  std::vector<SingularPoint> points;
  std::vector<SingularCurve> curves;
  /// True when ∇F vanishes on a two-dimensional part of F = 0 (F = G², e.g. the Kummer family
  /// at mu = 1/3): such parts are reported here and not traced.
  bool has_singular_sheet = false;
  Vec3 singular_sheet_example = Vec3::Zero();  ///< a point of that part, when there is one
  int seeds = 0;                               ///< grid points the search started from

  bool empty() const { return points.empty() && curves.empty() && !has_singular_sheet; }
  /// Points of one kind.
  std::vector<Vec3> points_of(SingularPointKind kind) const;
  /// Number of curves of one kind.
  int count(CurveKind kind) const;
  /// Distance from p to the nearest point or curve (infinity when there is none).
  double distance(const Vec3& p) const;
};

struct SingularSetOptions {
  int cells = 48;                 ///< seed grid cells along the longest side of the clip's box
  double spacing = 0;             ///< vertex spacing along curves; 0: half a seed cell
  int max_curve_points = 200000;  ///< over all curves: a bound on the work
};

/// Finds the singular set of `surface` inside its clip (which must be bounded: BadInput
/// otherwise). Deterministic; single-threaded; costs a grid of Hessians plus a few Newton steps
/// per curve vertex (milliseconds for the catalog's surfaces). Stops early, returning what it
/// has, when `stop` is requested.
SingularSet find_singular_set(const Surface& surface, const SingularSetOptions& options = {},
                              std::stop_token stop = {});

/// The set when the clip is bounded (find_singular_set with its defaults), none otherwise.
std::optional<SingularSet> find_singular_set_if_bounded(const Surface& surface,
                                                        std::stop_token stop = {});

/// The warning every command gives when ∇F vanishes on a whole sheet of F = 0 (F is a square
/// or worse there and never changes sign), or none. `known`: the set already found; without
/// it a coarse one is searched (24 cells) when the clip is bounded.
std::optional<std::string> singular_sheet_warning(const Surface& surface, const SingularSet* known);

/// The set as JSON: {"points": [{"kind", "position"}], "curves": [{"kind", "closed", "length",
/// "points"}], "singular_sheet": bool[, "singular_sheet_example"]}, for --json and --stats.
/// `with_polylines` false leaves out the curves' vertices (ends only).
nlohmann::json singular_set_json(const SingularSet& set, bool with_polylines = true);

/// One line: "3 crossing curves, 6 isolated; 1 triple, 6 pinch, 6 clip-end points".
std::string singular_set_summary(const SingularSet& set);

}  // namespace zeroset
