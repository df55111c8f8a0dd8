// Floaters held on the singular set (docs/algorithms.md B.7): one on each special point, a chain
// along each curve, the set found again when the parameters have come to rest.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "floater_state_detail.h"
#include "spatial_hash_detail.h"
#include "zeroset/detail/segment.h"

namespace zeroset::detail {

namespace {

// Spacing of the floaters along a curve, in units of their radius σ_s: a little closer than
// the sheets' floaters of that radius (about 1.8σ at the desired energy), so the curve is
// covered at the density of the sheets around it.
constexpr double kRailSpacing = 0.75;
// Each step a floater on a curve moves this fraction of the way to the midpoint of its
// neighbours on the curve (below 1/2, so it never passes one).
constexpr double kChainRate = 0.25;
// At most this share of max_count is held on the set (the sheets need the rest).
constexpr double kHeldShare = 0.25;
// The index answers distances up to min(γ_s, this many σ̂): near the set, where β depends on
// it; farther out the Newton step of B.3 estimates the distance.
constexpr double kReachNominal = 4;
// A free floater closer than this fraction of the spacing to an isolated curve has left every
// sheet: it is removed (the curve's own floaters sample it).
constexpr double kIsolatedStray = 0.5;
// A gap along a chain wider than this fraction of the spacing of the sheets' floaters around it
// gets one more floater. The sheets set the scale a sampling is judged by, and near a pinch
// point, where two half-sheets fold together, they pack tighter than any global rule for the
// chain knows; below 1, because the sheets keep settling after the last look.
constexpr double kChainToSheets = 0.85;
// The sheets' spacing at a place: the mean nearest-neighbour distance of this many free
// floaters nearest to it (measure_singular_coverage's measure), when they are all within this
// many chain spacings. Farther sheets set no bound there (an isolated curve far from any sheet),
// and the search stays short; the gaps near the sheets that are split spread along the chain.
constexpr std::size_t kSpacingNeighbours = 8;
constexpr double kSpacingReach = 8;

// The set serves the β estimator and the floaters held on it.
bool uses_set(const FloaterState& sys) {
  return sys.opt.snap_to_nodes || sys.opt.radius_adapt == RadiusAdapt::kSingular ||
         sys.opt.radius_adapt == RadiusAdapt::kMixed;
}

// μ at a singular point, where α_i and β_i vanish: the fission radius of the floaters there.
double singular_factor(const FloaterOptions& o) {
  return o.radius_adapt == RadiusAdapt::kWitkinHeckbert ? 1.0 : o.min_radius_factor;
}

void index_set(FloaterState& sys) {
  const double reach = std::min(sys.singular_scale, kReachNominal * sys.sigma_hat);
  sys.singular_index = sys.singular.empty() || !(reach > 0) ? SingularSetIndex()
                                                            : SingularSetIndex(sys.singular, reach);
}

// The arc length of the point of curve c nearest to p, and its distance.
std::pair<double, double> project_on(const RailCurve& c, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity(), at = 0;
  for (std::size_t k = 0; k + 1 < c.points.size(); ++k) {
    const Vec3 d = c.points[k + 1] - c.points[k];
    const double t = detail::segment_parameter(p, c.points[k], c.points[k + 1]);
    const double dist = (p - (c.points[k] + t * d)).norm();
    if (dist < best) best = dist, at = c.arc[k] + t * (c.arc[k + 1] - c.arc[k]);
  }
  return {at, best};
}

struct Seat {
  Vec3 p;
  std::int32_t curve;  // -1: a point
  double arc;
};

// The seats of the held floaters: the special points other than nodes (those are left to
// snapping, which follows them while parameters move), the ends of open curves, and along
// every curve evenly spaced seats between the points on it, about rail_spacing apart.
std::vector<Seat> seats(FloaterState& sys) {
  std::vector<Seat> out;
  // The ends of curves and the special points found on them agree to about 1e-12 of the
  // scene radius; one floater holds both.
  const double tiny = 1e-6 * sys.scene_radius;
  auto add_point = [&](const Vec3& p) {
    for (const Seat& s : out)
      if ((s.p - p).norm() <= tiny) return;
    out.push_back({p, -1, 0});
  };
  for (const SingularPoint& q : sys.singular.points)
    if (q.kind != SingularPointKind::kNode) add_point(q.position);
  double total = 0;
  for (const RailCurve& c : sys.rails) {
    total += c.length();
    if (c.closed || c.length() == 0) continue;
    add_point(c.points.front());
    add_point(c.points.back());
  }
  const std::size_t points = out.size();
  const double budget =
      kHeldShare * static_cast<double>(sys.opt.max_count) - static_cast<double>(points);
  sys.rail_sigma = singular_factor(sys.opt) * sigma_max(sys);
  sys.rail_spacing = kRailSpacing * sys.rail_sigma;
  if (budget < 1 || total == 0) return out;
  if (total / sys.rail_spacing > budget) {
    sys.rail_spacing = total / budget;
    sys.rail_sigma = sys.rail_spacing / kRailSpacing;
  }
  const double h = sys.rail_spacing;
  for (std::size_t ci = 0; ci < sys.rails.size(); ++ci) {
    RailCurve& c = sys.rails[ci];
    c.fixed.clear();
    const double length = c.length();
    if (length == 0) continue;
    // Breaks: the points held on the curve (its ends, triple points inside it).
    std::vector<double> breaks;
    for (std::size_t k = 0; k < points; ++k) {
      const auto [at, dist] = project_on(c, out[k].p);
      if (dist <= 1e-6 * sys.scene_radius) breaks.push_back(at);
    }
    std::sort(breaks.begin(), breaks.end());
    sys.rails[ci].fixed = breaks;
    auto add_piece = [&](double a, double b, bool from_a) {
      const auto pieces = static_cast<int>(std::ceil((b - a) / h - 1e-9));
      const int first = from_a ? 0 : 1;
      for (int k = first; k < pieces; ++k)
        out.push_back({Vec3::Zero(), static_cast<std::int32_t>(ci),
                       c.keep(a + (b - a) * k / std::max(pieces, 1))});
    };
    if (breaks.empty() && c.closed) {
      add_piece(0, length, true);
    } else if (c.closed) {
      for (std::size_t k = 0; k + 1 < breaks.size(); ++k)
        add_piece(breaks[k], breaks[k + 1], false);
      add_piece(breaks.back(), breaks.front() + length, false);
    } else {
      if (breaks.empty() || breaks.front() > 0) breaks.insert(breaks.begin(), 0.0);
      if (breaks.back() < length) breaks.push_back(length);
      for (std::size_t k = 0; k + 1 < breaks.size(); ++k)
        add_piece(breaks[k], breaks[k + 1], false);
    }
  }
  for (Seat& s : out)
    if (s.curve >= 0) s.p = sys.rails[static_cast<std::size_t>(s.curve)].at(s.arc);
  return out;
}

// Places the held floaters; free floaters on top of them (within half a spacing of a curve or
// special point) make room, and so do the last free floaters when the cap is reached. Returns
// the numbers inserted and removed.
SingularEvents place(FloaterState& sys) {
  SingularEvents events;
  const std::vector<Seat> wanted = seats(sys);
  if (wanted.empty()) return events;
  std::vector<std::uint32_t> gone;
  const double room = 0.5 * sys.rail_spacing;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < floater_count(sys); ++i) {
    if (sys.pinned[i] == kFree) {
      const auto near = sys.singular_index.nearest(sys.pos[i]);
      const bool on_held =
          near.distance < room &&
          (near.curve >= 0 || sys.singular.points[static_cast<std::size_t>(near.point)].kind !=
                                  SingularPointKind::kNode);
      if (on_held) {
        gone.push_back(static_cast<std::uint32_t>(i));
        continue;
      }
    }
    ++kept;
  }
  for (std::size_t i = floater_count(sys); i-- > 0 && kept + wanted.size() > sys.opt.max_count;) {
    if (sys.pinned[i] != kFree || std::binary_search(gone.begin(), gone.end(), i)) continue;
    gone.insert(std::lower_bound(gone.begin(), gone.end(), i), static_cast<std::uint32_t>(i));
    --kept;
  }
  remove_floaters(sys, gone);
  events.removed = gone.size();
  for (const Seat& s : wanted) {
    if (floater_count(sys) >= sys.opt.max_count) break;
    push_floater(sys, s.p, sys.rail_sigma, singular_factor(sys.opt));
    sys.pinned.back() = s.curve >= 0 ? kOnCurve : kOnPoint;
    sys.rail.back() = s.curve;
    sys.arc.back() = s.arc;
    ++events.inserted;
  }
  return events;
}

// Splits every gap along a chain that is wider than kChainToSheets times the spacing of the
// free floaters around it: one floater at its middle per gap and upkeep (the chain's dynamics
// spread it), within the held share. At the cap the free floaters where the sheets are
// densest make room. The chains are placed while the sheets are still sparse; this lets them
// follow as the sheets fill in and tighten. Returns the numbers inserted and removed.
SingularEvents split_chain_gaps(FloaterState& sys) {
  SingularEvents events;
  if (sys.rails.empty()) return events;
  std::vector<Vec3> sheets;
  std::vector<std::uint32_t> sheet_index;
  std::size_t held = 0;
  for (std::size_t i = 0; i < floater_count(sys); ++i) {
    if (sys.pinned[i] == kFree) {
      sheets.push_back(sys.pos[i]);
      sheet_index.push_back(static_cast<std::uint32_t>(i));
    } else if (sys.pinned[i] >= kOnPoint) {
      ++held;
    }
  }
  const double share = kHeldShare * static_cast<double>(sys.opt.max_count);
  if (sheets.size() < 2 || static_cast<double>(held) >= share) return events;
  Box3 box{sheets[0], sheets[0]};
  for (const Vec3& p : sheets) {
    box.lo = box.lo.cwiseMin(p);
    box.hi = box.hi.cwiseMax(p);
  }
  const double extent = std::max(box.size().maxCoeff(), 1e-12 * sys.scene_radius);
  SpatialHash grid;
  grid.build(sheets, box, 1.5 * extent / std::sqrt(static_cast<double>(sheets.size())));
  std::vector<double> nn(sheets.size(), -1);
  auto nearest_of = [&](std::uint32_t j) {
    if (nn[j] < 0) nn[j] = grid.nearest(sheets[j], sheets, j).second;
    return nn[j];
  };
  const double reach = kSpacingReach * sys.rail_spacing;
  auto spacing = [&](const Vec3& q) {
    const auto near = grid.k_nearest(q, sheets, kSpacingNeighbours, reach);
    // Fewer than that within reach: a spacing of one or two floaters says little.
    if (near.size() < kSpacingNeighbours) return std::numeric_limits<double>::infinity();
    double sum = 0;
    for (std::uint32_t j : near) sum += nearest_of(j);
    return sum / static_cast<double>(near.size());
  };
  std::vector<std::vector<double>> on(sys.rails.size());
  for (std::size_t i = 0; i < floater_count(sys); ++i)
    if (sys.pinned[i] == kOnCurve) on[static_cast<std::size_t>(sys.rail[i])].push_back(sys.arc[i]);
  std::vector<Seat> wanted;
  for (std::size_t c = 0; c < sys.rails.size(); ++c) {
    const RailCurve& curve = sys.rails[c];
    std::vector<double>& list = on[c];
    list.insert(list.end(), curve.fixed.begin(), curve.fixed.end());
    if (list.empty() || curve.length() == 0) continue;
    std::sort(list.begin(), list.end());
    if (curve.closed) list.push_back(list.front() + curve.length());
    // The sheets' spacing at each floater and held point of the chain; a gap takes the
    // smaller of its ends'. An isolated curve has no sheet of its own: the sheets it meets
    // (at a pinch point) are its scale all along, the smallest spacing found on it.
    std::vector<double> at_point(list.size());
    for (std::size_t k = 0; k < list.size(); ++k)
      at_point[k] = curve.closed && k + 1 == list.size() ? at_point[0]
                                                         : spacing(curve.at(curve.keep(list[k])));
    if (curve.kind == CurveKind::kIsolated)
      std::fill(at_point.begin(), at_point.end(),
                *std::min_element(at_point.begin(), at_point.end()));
    for (std::size_t k = 0; k + 1 < list.size(); ++k) {
      const double a = list[k], b = list[k + 1];
      const double mid = curve.keep(0.5 * (a + b));
      if (b - a > kChainToSheets * std::min(at_point[k], at_point[k + 1]))
        wanted.push_back({curve.at(mid), static_cast<std::int32_t>(c), mid});
    }
  }
  const auto room =
      static_cast<std::size_t>(share) - std::min(held, static_cast<std::size_t>(share));
  if (wanted.size() > room) wanted.resize(room);
  if (wanted.empty()) return events;
  // At the cap: the free floaters with the nearest neighbours go.
  const std::size_t free_slots =
      sys.opt.max_count - std::min(sys.opt.max_count, floater_count(sys));
  if (wanted.size() > free_slots) {
    const std::size_t excess = std::min(wanted.size() - free_slots, sheets.size());
    std::vector<std::uint32_t> order(sheets.size());
    std::iota(order.begin(), order.end(), 0u);
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(excess),
                      order.end(), [&](std::uint32_t x, std::uint32_t y) {
                        return nearest_of(x) < nearest_of(y) ||
                               (nearest_of(x) == nearest_of(y) && x < y);
                      });
    std::vector<std::uint32_t> gone;
    for (std::size_t k = 0; k < excess; ++k) gone.push_back(sheet_index[order[k]]);
    std::sort(gone.begin(), gone.end());
    remove_floaters(sys, gone);
    events.removed = gone.size();
  }
  for (const Seat& s : wanted) {
    if (floater_count(sys) >= sys.opt.max_count) break;
    push_floater(sys, s.p, sys.rail_sigma, singular_factor(sys.opt));
    sys.pinned.back() = kOnCurve;
    sys.rail.back() = s.curve;
    sys.arc.back() = s.arc;
    ++events.inserted;
  }
  return events;
}

// Free floaters that have come onto an isolated curve: no sheet passes there, so they have left
// the surface's sheets (F has a strict extremum across the curve and pulls them in).
std::size_t remove_isolated_strays(FloaterState& sys) {
  std::vector<std::uint32_t> gone;
  const double near = kIsolatedStray * sys.rail_spacing;
  for (std::size_t i = 0; i < floater_count(sys); ++i) {
    if (sys.pinned[i] != kFree) continue;
    const auto nearest = sys.singular_index.nearest(sys.pos[i]);
    if (nearest.curve >= 0 && nearest.distance < near &&
        sys.rails[static_cast<std::size_t>(nearest.curve)].kind == CurveKind::kIsolated)
      gone.push_back(static_cast<std::uint32_t>(i));
  }
  remove_floaters(sys, gone);
  return gone.size();
}

std::size_t remove_held(FloaterState& sys) {
  std::vector<std::uint32_t> gone;
  for (std::size_t i = 0; i < floater_count(sys); ++i)
    if (sys.pinned[i] >= kOnPoint) gone.push_back(static_cast<std::uint32_t>(i));
  remove_floaters(sys, gone);
  sys.singular_placed = false;
  return gone.size();
}

}  // namespace

// Along a curve the floaters feel their two neighbours on it only (the held points on it fixed):
// each moves a quarter of the way towards the midpoint between them per step, the gradient
// flow of the sum of the squared gaps, whose minimum is even spacing. Sheets pushing them
// along would bunch them and open gaps; and the pair force of A.2, which vanishes at zero
// distance, lets the end of a chain collapse onto a held point.
void chain_velocities(FloaterState& sys) {
  const std::size_t n = floater_count(sys);
  fit(sys.rail_push, n);
  if (!sys.singular_placed || sys.rails.empty()) return;
  std::vector<std::vector<std::pair<double, std::int64_t>>> on(sys.rails.size());
  for (std::size_t i = 0; i < n; ++i)
    if (sys.pinned[i] == kOnCurve)
      on[static_cast<std::size_t>(sys.rail[i])].emplace_back(sys.arc[i],
                                                             static_cast<std::int64_t>(i));
  for (std::size_t c = 0; c < sys.rails.size(); ++c) {
    auto& list = on[c];
    if (list.empty()) continue;
    const RailCurve& curve = sys.rails[c];
    for (double f : curve.fixed) list.emplace_back(f, -1);
    std::sort(list.begin(), list.end());
    const auto m = static_cast<std::int64_t>(list.size());
    const double length = curve.length();
    for (std::int64_t k = 0; k < m; ++k) {
      const std::int64_t i = list[static_cast<std::size_t>(k)].second;
      if (i < 0) continue;
      const double s = list[static_cast<std::size_t>(k)].first;
      // The neighbours' arc lengths (around a closed curve, across its start); an open curve's
      // ends bound a chain that has no held point there.
      double lo = 0, hi = length;
      if (k > 0)
        lo = list[static_cast<std::size_t>(k - 1)].first;
      else if (curve.closed)
        lo = list[static_cast<std::size_t>(m - 1)].first - length;
      if (k + 1 < m)
        hi = list[static_cast<std::size_t>(k + 1)].first;
      else if (curve.closed)
        hi = list[0].first + length;
      sys.rail_push[static_cast<std::size_t>(i)] = kChainRate * (0.5 * (lo + hi) - s) / sys.opt.dt;
    }
  }
}

void find_singular(FloaterState& sys) {
  sys.singular = {};
  sys.rails.clear();
  sys.singular_current = false;
  sys.singular_placed = false;
  if (!uses_set(sys)) {
    index_set(sys);
    return;
  }
  sys.singular = find_singular_set(sys.surface, {}, sys.stop);
  for (const SingularCurve& curve : sys.singular.curves) {
    RailCurve c;
    c.points = curve.points;
    c.closed = curve.closed;
    c.kind = curve.kind;
    c.arc.assign(1, 0.0);
    for (std::size_t k = 1; k < c.points.size(); ++k)
      c.arc.push_back(c.arc.back() + (c.points[k] - c.points[k - 1]).norm());
    if (c.points.size() < 2) {  // kept, so rails[k] is curves[k]; a point has no length
      c.points.assign(2, curve.points.empty() ? Vec3(Vec3::Zero()) : curve.points[0]);
      c.arc.assign(2, 0.0);
    }
    sys.rails.push_back(std::move(c));
  }
  index_set(sys);
  sys.singular_current = true;
}

SingularEvents keep_singular_floaters(FloaterState& sys) {
  SingularEvents events;
  if (!uses_set(sys)) return events;
  if (!sys.singular_current) {
    if (sys.still_steps < static_cast<std::size_t>(sys.opt.estimator_interval)) return events;
    find_singular(sys);
  }
  if (!sys.opt.snap_to_nodes) return events;
  if (!sys.singular_placed) {
    events = place(sys);
    sys.singular_placed = true;
  } else {
    events = split_chain_gaps(sys);
  }
  events.removed += remove_isolated_strays(sys);
  return events;
}

std::size_t drop_singular_set(FloaterState& sys) {
  const std::size_t removed = remove_held(sys);
  sys.singular_current = false;
  sys.still_steps = 0;
  return removed;
}

std::size_t replace_singular_floaters(FloaterState& sys) {
  const std::size_t removed = remove_held(sys);
  if (sys.singular_current && uses_set(sys))
    index_set(sys);
  else
    sys.singular_current = false;
  return removed;
}

}  // namespace zeroset::detail
