// The singular set: seeds from a grid, Newton onto S, curves traced and classified, then the
// special points (triple points where curves meet, pinch points where the kind changes, ends on
// the clip). See docs/singular.md.
#include "zeroset/surface/singular_set.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

#include <fmt/core.h>

#include "singular_detail.h"
#include "zeroset/error.h"
#include "zeroset/io/memory.h"
#include "zeroset/surface/json_read.h"

namespace zeroset {
namespace {

using detail::SingularScales;

constexpr double kSqrt3 = 1.7320508075688772;

// F, ∇F and H at the nodes of a grid over the clip's box, in rows along x.
struct GridSamples {
  std::array<int, 3> n{0, 0, 0};
  Vec3 origin = Vec3::Zero();
  double cell = 1;
  std::vector<double> f;
  std::vector<Vec3> g;
  std::vector<Mat3> h;
  Vec3 point(size_t i) const {
    const size_t nx = static_cast<size_t>(n[0]), ny = static_cast<size_t>(n[1]);
    return origin + cell * Vec3(static_cast<double>(i % nx), static_cast<double>((i / nx) % ny),
                                static_cast<double>(i / (nx * ny)));
  }
};

/// The grid's spacing and node counts for `cells` cells along the box's longest side.
void size_grid(const Box3& box, int cells, GridSamples& gs) {
  gs.cell = box.size().maxCoeff() / cells;
  for (int a = 0; a < 3; ++a)
    gs.n[static_cast<size_t>(a)] =
        std::max(2, static_cast<int>(std::ceil(box.size()[a] / gs.cell - 1e-9)) + 1);
}

// Bytes per grid node: F, ∇F and the Hessian.
constexpr double kBytesPerNode = sizeof(double) + sizeof(Vec3) + sizeof(Mat3);

/// Refuses a grid that does not fit in the memory the process may still take, naming the
/// largest number of cells that does.
void check_grid_memory(const Box3& box, int cells) {
  const MemoryLimit have = available_memory();
  if (!have.known) return;
  auto need = [&](int n) {
    GridSamples gs;
    size_grid(box, n, gs);
    return kBytesPerNode * gs.n[0] * static_cast<double>(gs.n[1]) * gs.n[2];
  };
  const double needed = need(cells);
  if (needed <= have.budget()) return;
  int fits = cells;
  while (fits > 4 && need(fits) > have.budget()) fits = fits * 4 / 5;
  throw InvalidArgument("singular set cells", std::to_string(cells),
                        fmt::format("a grid of {} cells {}; use {} cells or fewer", cells,
                                    memory_shortfall(needed, have), fits));
}

// Stops after the row in which `stop` is requested (the samples are then incomplete).
GridSamples sample_grid(const Field& field, const Box3& box, int cells,
                        const std::stop_token& stop) {
  GridSamples gs;
  size_grid(box, cells, gs);
  gs.origin = box.center() - 0.5 * gs.cell * Vec3(gs.n[0] - 1, gs.n[1] - 1, gs.n[2] - 1);
  const size_t nx = static_cast<size_t>(gs.n[0]);
  const size_t total = nx * static_cast<size_t>(gs.n[1]) * static_cast<size_t>(gs.n[2]);
  gs.f.resize(total);
  gs.g.resize(total);
  gs.h.resize(total);
  Evaluator ev(field);
  std::vector<double> x(nx), y(nx), z(nx), f(nx), gx(nx), gy(nx), gz(nx);
  std::array<std::vector<double>, 6> hv;
  for (auto& v : hv) v.resize(nx);
  for (size_t row = 0; row < total / nx && !stop.stop_requested(); ++row) {
    for (size_t i = 0; i < nx; ++i) {
      const Vec3 p = gs.point(row * nx + i);
      x[i] = p.x(), y[i] = p.y(), z[i] = p.z();
    }
    ev.values_gradients_hessians(x, y, z, f, gx, gy, gz,
                                 {hv[0], hv[1], hv[2], hv[3], hv[4], hv[5]});
    for (size_t i = 0; i < nx; ++i) {
      const size_t k = row * nx + i;
      gs.f[k] = f[i];
      gs.g[k] = Vec3(gx[i], gy[i], gz[i]);
      gs.h[k] << hv[0][i], hv[1][i], hv[2][i], hv[1][i], hv[3][i], hv[4][i], hv[2][i], hv[4][i],
          hv[5][i];
    }
  }
  return gs;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// Length of the minimum-norm Gauss–Newton step towards S from a grid node: short steps mark
// nodes close to S (the first step of detail::converge_to_singular, from the stored samples).
double first_step_length(double f, const Vec3& g, const Mat3& h, double cell) {
  const auto step = detail::singular_gauss_newton_step<3>(f, g, h, Mat3::Identity(), cell);
  return step ? step->norm() : std::numeric_limits<double>::infinity();
}

double distance_to_curves(const Vec3& p, const std::vector<SingularCurve>& curves) {
  double best = std::numeric_limits<double>::infinity();
  for (const SingularCurve& c : curves)
    for (size_t i = 0; i + 1 < c.points.size(); ++i)
      best = std::min(best, detail::segment_distance(p, c.points[i], c.points[i + 1]));
  return best;
}

// Sets S on a two-dimensional part of F = 0 (F = G²) apart from curves: around such a point
// every direction of the Hessian's null space leads to more points of S.
bool on_singular_sheet(Evaluator& ev, const Vec3& p, const detail::HessianShape& shape,
                       const SingularScales& s) {
  for (int k = 1; k < 3; ++k)
    for (double sign : {-1.0, 1.0}) {
      const Vec3 dir = shape.vectors.col(k);
      const detail::Converged c =
          detail::converge_in_plane(ev, p + sign * s.cell * dir, dir, s, 0.5 * s.cell);
      if (!c.ok) return false;
    }
  return true;
}

// The direction of a cuspidal edge (F ≈ u² − v³ across it, so H has rank one all along) through
// p, where H has two null vectors and p is not on a sheet. The null vectors then mix the
// tangent with the direction across the cusp, and a walk along either stalls. The curve
// crosses the plane normal to either null vector d at p + spacing·d unless d is normal to it;
// the crossing closest to its start (the better conditioned one) gives the chord from p. Zero
// when the curve crosses neither within reach, or where H there has rank two: p was a pinch
// point, and the curve through it is traced from other seeds.
Vec3 probe_curve_direction(Evaluator& ev, const Vec3& p, const detail::HessianShape& shape,
                           const SingularScales& s, double spacing) {
  Vec3 best = Vec3::Zero();
  double best_move = 2 * spacing;
  for (int k = 1; k < 3; ++k) {
    const Vec3 d = shape.vectors.col(k);
    const detail::Converged c = detail::converge_in_plane(ev, p + spacing * d, d, s, best_move);
    if (c.ok && (c.p - p - spacing * d).norm() < best_move &&
        detail::rank_one_hessian(ev.sample(c.p, Derivatives::kHessian).hessian, s.hess)) {
      best_move = (c.p - p - spacing * d).norm();
      best = (c.p - p).normalized();
    }
  }
  return best;
}

// Traces the curve of S through p in both directions along t; empty when it does not move.
SingularCurve trace_through(Evaluator& ev, const Clip& clip, const Vec3& p, const Vec3& t,
                            const SingularScales& s, double spacing, int& budget) {
  SingularCurve curve;
  detail::WalkEnd end_fwd{}, end_back{};
  std::vector<Vec3> fwd = detail::walk_curve(ev, clip, p, t, s, spacing, budget, end_fwd);
  if (end_fwd == detail::WalkEnd::kClosed) {
    curve.points.push_back(p);
    curve.points.insert(curve.points.end(), fwd.begin(), fwd.end());
    curve.points.push_back(p);
    curve.closed = true;
    return curve;
  }
  std::vector<Vec3> back = detail::walk_curve(ev, clip, p, -t, s, spacing, budget, end_back);
  curve.points.assign(back.rbegin(), back.rend());
  curve.points.push_back(p);
  curve.points.insert(curve.points.end(), fwd.begin(), fwd.end());
  if (curve.points.size() < 2) curve.points.clear();
  return curve;
}

// Puts `q` into the polyline as a vertex where it lies on it (within `near` of a segment).
void insert_vertex(SingularCurve& c, const Vec3& q, double near) {
  size_t best = c.points.size();
  double best_d = near;
  for (size_t i = 0; i + 1 < c.points.size(); ++i) {
    const double d = detail::segment_distance(q, c.points[i], c.points[i + 1]);
    if (d <= best_d) best_d = d, best = i;
  }
  if (best == c.points.size()) return;
  const double tiny = 1e-3 * near;
  if ((c.points[best] - q).norm() <= tiny) {
    c.points[best] = q;
  } else if ((c.points[best + 1] - q).norm() <= tiny) {
    c.points[best + 1] = q;
  } else {
    c.points.insert(c.points.begin() + static_cast<std::ptrdiff_t>(best + 1), q);
  }
}

void add_point(std::vector<SingularPoint>& points, const Vec3& p, SingularPointKind kind,
               double same) {
  for (const SingularPoint& q : points)
    if ((q.position - p).norm() < same) return;
  points.push_back({p, kind});
}

}  // namespace

std::string_view to_string(CurveKind kind) {
  switch (kind) {
    case CurveKind::kCrossing:
      return "crossing";
    case CurveKind::kIsolated:
      return "isolated";
    case CurveKind::kDegenerate:
      return "degenerate";
  }
  return "?";
}

std::string_view to_string(SingularPointKind kind) {
  switch (kind) {
    case SingularPointKind::kNode:
      return "node";
    case SingularPointKind::kPinch:
      return "pinch";
    case SingularPointKind::kTriple:
      return "triple";
    case SingularPointKind::kClipEnd:
      return "clip end";
    case SingularPointKind::kDegenerate:
      return "degenerate";
  }
  return "?";
}

double SingularCurve::length() const {
  double l = 0;
  for (size_t i = 0; i + 1 < points.size(); ++i) l += (points[i + 1] - points[i]).norm();
  return l;
}

std::vector<Vec3> SingularSet::points_of(SingularPointKind kind) const {
  std::vector<Vec3> out;
  for (const SingularPoint& p : points)
    if (p.kind == kind) out.push_back(p.position);
  return out;
}

int SingularSet::count(CurveKind kind) const {
  return static_cast<int>(
      std::count_if(curves.begin(), curves.end(), [&](const auto& c) { return c.kind == kind; }));
}

double SingularSet::distance(const Vec3& p) const {
  double best = distance_to_curves(p, curves);
  for (const SingularPoint& q : points) best = std::min(best, (q.position - p).norm());
  return best;
}

namespace {

// The search's fixed quantities, shared by its phases.
struct Search {
  const Clip& clip;
  const GridSamples& grid;
  SingularScales s;
  double radius = 0;
  double spacing = 0;     // vertex spacing along curves
  double same_point = 0;  // points closer than this are one
};

// Phase 1: the scales of ∇F and the Hessian near F = 0: at the nodes next to a sign change of
// F (a grid edge that F = 0 crosses), or where there is none (F = G², no sign change), at the
// nodes within a cell of F = 0 to first order. The sign change comes first because the
// first-order distance |F|/|∇F| can mislead by orders of magnitude: for (x²+y²+z²)^1000 − 1 it
// is r/2000 at every node outside the sphere, whose gradients reach 10³⁰⁰, and a scale taken
// from them makes every point within 17% of the sphere look singular. Returns false when F
// and ∇F vanish at every node (F ≡ 0).
bool measure_scales(const GridSamples& grid, SingularScales& s) {
  std::vector<double> grads, hesses, near_grads, near_hesses;
  bool all_zero = true;
  const size_t nx = static_cast<size_t>(grid.n[0]), nxy = nx * static_cast<size_t>(grid.n[1]);
  auto crosses = [&](size_t i) {
    const double f = grid.f[i];
    const size_t strides[3] = {1, nx, nxy};
    const size_t index[3] = {i % nx, (i / nx) % static_cast<size_t>(grid.n[1]), i / nxy};
    for (int a = 0; a < 3; ++a) {
      if (index[a] + 1 >= static_cast<size_t>(grid.n[a])) continue;
      const double o = grid.f[i + strides[a]];
      if (std::isfinite(f) && std::isfinite(o) && (f == 0 || (f < 0) != (o < 0))) return true;
    }
    return false;
  };
  for (size_t i = 0; i < grid.f.size(); ++i) {
    const double gn = grid.g[i].norm();
    if (grid.f[i] != 0 || gn != 0) all_zero = false;
    if (!std::isfinite(gn)) continue;
    if (crosses(i)) {
      grads.push_back(gn);
      hesses.push_back(grid.h[i].norm());
    } else if (std::abs(grid.f[i]) <= gn * grid.cell) {
      near_grads.push_back(gn);
      near_hesses.push_back(grid.h[i].norm());
    }
  }
  if (all_zero) return false;
  if (grads.empty()) grads.swap(near_grads), hesses.swap(near_hesses);
  s.grad = median(grads);
  s.hess = median(hesses);
  if (!(s.grad > 0)) {
    // Near F = 0 the gradient vanishes at every grid node: F = G² or worse. Fall back to the
    // largest finite values for the scales so the search below can still confirm it.
    for (size_t i = 0; i < grid.f.size(); ++i)
      if (std::isfinite(grid.g[i].norm())) {
        s.grad = std::max(s.grad, grid.g[i].norm());
        s.hess = std::max(s.hess, grid.h[i].norm());
      }
  }
  return true;
}

// Phase 2: Gauss–Newton from every grid node whose first step is short; each point reached is
// a node, a point of a singular sheet, a start of curves traced both ways, or deferred (a
// singular Hessian and no curve yet: triple or degenerate points, phase 3).
void search_from_nodes(Evaluator& ev, const Search& z, int max_curve_points, std::stop_token stop,
                       SingularSet& out, std::vector<Vec3>& deferred) {
  const GridSamples& grid = z.grid;
  const Clip& clip = z.clip;
  int budget = max_curve_points;
  int sheet_hits = 0;
  for (size_t i = 0; i < grid.f.size(); ++i) {
    if (stop.stop_requested() || budget <= 0) break;
    const Vec3 node = grid.point(i);
    if (!clip.is_empty_spec() && !clip.contains(node, grid.cell)) continue;
    if (!(first_step_length(grid.f[i], grid.g[i], grid.h[i], grid.cell) <=
          1.5 * kSqrt3 * grid.cell))
      continue;
    ++out.seeds;
    const detail::Converged c = detail::converge_to_singular(ev, node, z.s, 3 * grid.cell);
    if (!c.ok || (!clip.is_empty_spec() && !clip.contains(c.p, 1e-9 * z.radius))) continue;
    if (distance_to_curves(c.p, out.curves) <= z.spacing) continue;
    const bool known = std::any_of(out.points.begin(), out.points.end(), [&](const auto& q) {
      return (q.position - c.p).norm() < z.same_point;
    });
    if (known) continue;
    const detail::HessianShape shape =
        detail::hessian_shape(ev.sample(c.p, Derivatives::kHessian).hessian);
    const int nullity = shape.nullity(z.s.hess);
    if (nullity == 0) {
      out.points.push_back({c.p, SingularPointKind::kNode});
      continue;
    }
    if (nullity == 2 && on_singular_sheet(ev, c.p, shape, z.s)) {
      if (++sheet_hits == 1) out.singular_sheet_example = c.p;
      if (sheet_hits >= 8) {
        out.has_singular_sheet = true;
        return;
      }
      continue;
    }
    if (nullity == 3) {  // H = 0: a triple point or worse; curves through it come from others
      deferred.push_back(c.p);
      continue;
    }
    std::vector<Vec3> directions;
    for (int k = 3 - nullity; k < 3; ++k) directions.push_back(shape.vectors.col(k));
    bool traced = false;
    for (size_t k = 0; !traced; ++k) {
      // Along the null vectors first (at a pinch or triple point one of them is the tangent);
      // where both stall, along the probed direction (a cuspidal edge).
      if (k == directions.size()) {
        const Vec3 d =
            nullity == 2 ? probe_curve_direction(ev, c.p, shape, z.s, z.spacing) : Vec3::Zero();
        if (d.isZero()) break;
        directions.push_back(d);
      }
      SingularCurve curve = trace_through(ev, clip, c.p, directions[k], z.s, z.spacing, budget);
      if (curve.points.size() >= 2) {
        out.curves.push_back(std::move(curve));
        traced = true;
      }
    }
    if (!traced) deferred.push_back(c.p);
  }
}

// Phase 3: triple points, where curves meet (each becomes a vertex of every curve through it),
// and the deferred points: on a curve with H = 0 a triple point, off every curve degenerate.
void add_triple_points(Evaluator& ev, const Search& z, const std::vector<Vec3>& deferred,
                       SingularSet& out) {
  std::vector<Vec3> triples;
  for (const SingularCurve& c : out.curves)
    for (const Vec3& q : detail::triple_points_on(ev, c, z.s, z.spacing))
      if (std::none_of(triples.begin(), triples.end(),
                       [&](const Vec3& p) { return (p - q).norm() < 0.5 * z.spacing; }))
        triples.push_back(q);
  for (const Vec3& q : triples) {
    add_point(out.points, q, SingularPointKind::kTriple, z.same_point);
    for (SingularCurve& c : out.curves) insert_vertex(c, q, 0.3 * z.spacing);
  }
  for (const Vec3& q : deferred) {
    if (distance_to_curves(q, out.curves) <= z.spacing) {
      // A point with H = 0 on a curve where no second curve was found (e.g. a curve's cusp).
      if (detail::hessian_shape(ev.sample(q, Derivatives::kHessian).hessian).nullity(z.s.hess) == 3)
        add_point(out.points, q, SingularPointKind::kTriple, 0.5 * z.spacing);
      continue;
    }
    add_point(out.points, q, SingularPointKind::kDegenerate, 0.5 * z.spacing);
  }
}

// Phase 4: pinch points split curves by kind; curve ends on the clip are named.
void split_and_name_ends(Evaluator& ev, const Search& z, SingularSet& out) {
  std::vector<SingularCurve> pieces;
  std::vector<Vec3> pinches;
  for (const SingularCurve& c : out.curves)
    for (SingularCurve& piece : detail::split_by_kind(ev, c, z.s, pinches))
      pieces.push_back(std::move(piece));
  out.curves = std::move(pieces);
  for (const Vec3& q : pinches)
    add_point(out.points, q, SingularPointKind::kPinch, 0.5 * z.spacing);
  for (const SingularCurve& c : out.curves) {
    if (c.closed || z.clip.is_empty_spec()) continue;
    // A cuspidal edge's points are known across it only to about 1e-8 (docs/singular.md), and
    // so is where it leaves the clip.
    const double on_clip = (c.kind == CurveKind::kDegenerate ? 1e-7 : 1e-9) * z.radius;
    for (const Vec3& end : {c.points.front(), c.points.back()})
      if (std::abs(z.clip.value(end)) <= on_clip)
        add_point(out.points, end, SingularPointKind::kClipEnd, z.same_point);
  }
}

}  // namespace

SingularSet find_singular_set(const Surface& surface, const SingularSetOptions& options,
                              std::stop_token stop) {
  if (options.cells < 4 || options.cells > 1024)
    throw InvalidArgument("singular set cells", std::to_string(options.cells),
                          "must be between 4 and 1024");
  const Box3 box = surface.bounds();
  check_grid_memory(box, options.cells);
  const GridSamples grid = sample_grid(surface.field, box, options.cells, stop);
  if (stop.stop_requested()) return {};
  const double radius = surface.scene_radius();
  SingularScales scales;
  scales.radius = radius;
  scales.cell = grid.cell;
  Search z{.clip = surface.clip,
           .grid = grid,
           .s = scales,
           .radius = radius,
           .spacing = options.spacing > 0 ? options.spacing : 0.5 * grid.cell,
           .same_point = 1e-6 * radius};
  SingularSet out;
  if (!measure_scales(grid, z.s)) {  // F ≡ 0: every point is singular
    out.has_singular_sheet = true;
    out.singular_sheet_example = box.center();
    return out;
  }
  if (!(z.s.grad > 0) || !(z.s.hess > 0) || !std::isfinite(z.s.grad)) return out;
  Evaluator ev(surface.field);
  std::vector<Vec3> deferred;
  search_from_nodes(ev, z, options.max_curve_points, stop, out, deferred);
  if (out.has_singular_sheet) {
    out.curves.clear();
    out.points.clear();
    return out;
  }
  if (stop.stop_requested()) return out;
  add_triple_points(ev, z, deferred, out);
  split_and_name_ends(ev, z, out);
  return out;
}

std::optional<SingularSet> find_singular_set_if_bounded(const Surface& surface,
                                                        std::stop_token stop) {
  if (!surface.clip.is_bounded()) return std::nullopt;
  return find_singular_set(surface, {}, stop);
}

std::optional<std::string> singular_sheet_warning(const Surface& surface,
                                                  const SingularSet* known) {
  if (!known && !surface.clip.is_bounded()) return std::nullopt;
  const SingularSet set = known ? *known : find_singular_set(surface, {.cells = 24});
  if (!set.has_singular_sheet) return std::nullopt;
  const Vec3& p = set.singular_sheet_example;
  return fmt::format(
      "{}: grad F vanishes on a whole sheet of F = 0 (e.g. at ({:.6g}, {:.6g}, "
      "{:.6g})): F is a square or worse there and never changes sign; mesh or "
      "sample G where F = G^2",
      surface.label(), p.x(), p.y(), p.z());
}

nlohmann::json singular_set_json(const SingularSet& set, bool with_polylines) {
  nlohmann::json j;
  j["points"] = nlohmann::json::array();
  for (const SingularPoint& p : set.points)
    j["points"].push_back(
        {{"kind", to_string(p.kind)}, {"position", json_read::from_vec3(p.position)}});
  j["curves"] = nlohmann::json::array();
  for (const SingularCurve& c : set.curves) {
    nlohmann::json jc = {{"kind", to_string(c.kind)},
                         {"closed", c.closed},
                         {"length", c.length()},
                         {"vertices", c.points.size()},
                         {"from", json_read::from_vec3(c.points.front())},
                         {"to", json_read::from_vec3(c.points.back())}};
    if (with_polylines) {
      jc["points"] = nlohmann::json::array();
      for (const Vec3& p : c.points) jc["points"].push_back(json_read::from_vec3(p));
    }
    j["curves"].push_back(std::move(jc));
  }
  j["singular_sheet"] = set.has_singular_sheet;
  if (set.has_singular_sheet)
    j["singular_sheet_example"] = json_read::from_vec3(set.singular_sheet_example);
  return j;
}

std::string singular_set_summary(const SingularSet& set) {
  if (set.has_singular_sheet)
    return "grad F vanishes on a whole sheet of F = 0 (F is a square or worse)";
  if (set.empty()) return "none found";
  std::string curves, points;
  for (CurveKind k : {CurveKind::kCrossing, CurveKind::kIsolated, CurveKind::kDegenerate})
    if (const int n = set.count(k); n > 0)
      curves += fmt::format("{}{} {} curve{}", curves.empty() ? "" : ", ", n, to_string(k),
                            n == 1 ? "" : "s");
  for (SingularPointKind k :
       {SingularPointKind::kNode, SingularPointKind::kTriple, SingularPointKind::kPinch,
        SingularPointKind::kDegenerate, SingularPointKind::kClipEnd})
    if (const size_t n = set.points_of(k).size(); n > 0)
      points +=
          fmt::format("{}{} {}{}", points.empty() ? "" : ", ", n,
                      k == SingularPointKind::kNode ? "node" : std::string(to_string(k)) + " point",
                      n == 1 ? "" : "s");
  if (curves.empty()) return points;
  if (points.empty()) return curves;
  return curves + "; " + points;
}

}  // namespace zeroset
