// A grid over the singular set's features for nearest-feature queries within a reach.
#include "zeroset/surface/singular_index.h"

#include <algorithm>
#include <cmath>

#include "zeroset/detail/segment.h"
#include "zeroset/error.h"

namespace zeroset {
namespace {

// The grid has at most this many cells along its longest side (memory and build time), and
// cells at most a quarter of the reach, so a cell's list holds little beyond the features
// that can be nearest in it.
constexpr double kMaxCellsPerSide = 96;
constexpr double kCellsPerReach = 4;

}  // namespace

SingularSetIndex::SingularSetIndex(const SingularSet& set, double reach) : reach_(reach) {
  if (!(reach > 0) || !std::isfinite(reach))
    throw InvalidArgument("singular set index reach", std::to_string(reach), "must be positive");
  // Curves first: where a point is a curve's end (ties), the curve is named.
  for (std::size_t c = 0; c < set.curves.size(); ++c) {
    const auto& pts = set.curves[c].points;
    for (std::size_t i = 0; i + 1 < pts.size(); ++i)
      features_.push_back(
          {pts[i], pts[i + 1], static_cast<int>(c), -1, static_cast<std::uint32_t>(i)});
  }
  for (std::size_t k = 0; k < set.points.size(); ++k) {
    const Vec3& p = set.points[k].position;
    features_.push_back({p, p, -1, static_cast<int>(k), 0});
  }
  if (features_.empty()) return;
  Box3 box{features_[0].a, features_[0].a};
  for (const Feature& f : features_) {
    box.lo = box.lo.cwiseMin(f.a).cwiseMin(f.b);
    box.hi = box.hi.cwiseMax(f.a).cwiseMax(f.b);
  }
  box.lo -= Vec3::Constant(reach);
  box.hi += Vec3::Constant(reach);
  cell_ = std::max(reach / kCellsPerReach, box.size().maxCoeff() / kMaxCellsPerSide);
  origin_ = box.lo;
  for (int a = 0; a < 3; ++a)
    cells_[static_cast<std::size_t>(a)] =
        std::max(1, static_cast<int>(std::ceil(box.size()[a] / cell_)));
  const std::size_t total = static_cast<std::size_t>(cells_[0]) *
                            static_cast<std::size_t>(cells_[1]) *
                            static_cast<std::size_t>(cells_[2]);
  // A feature goes into the cells whose centre lies within reach + half a cell diagonal of it
  // (any point of such a cell may have it within reach); then a cell keeps only the features
  // that can be nearest somewhere in it: distance from the centre at most the least such
  // distance plus a cell diagonal (and never beyond reach plus half a diagonal).
  const double half_diagonal = 0.5 * std::sqrt(3.0) * cell_;
  const double near = reach + half_diagonal;
  auto centre = [&](int i, int j, int k) {
    return Vec3(origin_ + cell_ * Vec3(i + 0.5, j + 0.5, k + 0.5));
  };
  auto for_cells = [&](const Feature& f, auto&& visit) {
    std::array<int, 6> r{};
    for (int a = 0; a < 3; ++a) {
      const double lo = std::min(f.a[a], f.b[a]) - near, hi = std::max(f.a[a], f.b[a]) + near;
      r[static_cast<std::size_t>(a)] =
          std::max(0, static_cast<int>(std::floor((lo - origin_[a]) / cell_)));
      r[static_cast<std::size_t>(a + 3)] =
          std::min(cells_[static_cast<std::size_t>(a)] - 1,
                   static_cast<int>(std::floor((hi - origin_[a]) / cell_)));
    }
    for (int k = r[2]; k <= r[5]; ++k)
      for (int j = r[1]; j <= r[4]; ++j)
        for (int i = r[0]; i <= r[3]; ++i) {
          const Vec3 c = centre(i, j, k);
          const double d =
              (c - (f.a + detail::segment_parameter(c, f.a, f.b) * (f.b - f.a))).norm();
          if (d <= near)
            visit(static_cast<std::size_t>(i) +
                      static_cast<std::size_t>(cells_[0]) *
                          (static_cast<std::size_t>(j) +
                           static_cast<std::size_t>(cells_[1]) * static_cast<std::size_t>(k)),
                  d);
        }
  };
  std::vector<double> least(total, std::numeric_limits<double>::infinity());
  for (const Feature& f : features_)
    for_cells(f, [&](std::size_t c, double d) { least[c] = std::min(least[c], d); });
  auto keeps = [&](std::size_t c, double d) { return d <= least[c] + 2 * half_diagonal; };
  start_.assign(total + 1, 0);
  for (const Feature& f : features_)
    for_cells(f, [&](std::size_t c, double d) { start_[c + 1] += keeps(c, d) ? 1 : 0; });
  for (std::size_t c = 0; c < total; ++c) start_[c + 1] += start_[c];
  items_.resize(start_[total]);
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (std::uint32_t f = 0; f < features_.size(); ++f)
    for_cells(features_[f], [&](std::size_t c, double d) {
      if (keeps(c, d)) items_[fill[c]++] = f;
    });
}

SingularSetIndex::Nearest SingularSetIndex::nearest(const Vec3& p) const {
  Nearest best;
  if (features_.empty()) return best;
  std::size_t c = 0, stride = 1;
  for (int a = 0; a < 3; ++a) {
    const double u = std::floor((p[a] - origin_[a]) / cell_);
    if (!(u >= 0 && u < cells_[static_cast<std::size_t>(a)])) return best;  // beyond reach (or NaN)
    c += static_cast<std::size_t>(u) * stride;
    stride *= static_cast<std::size_t>(cells_[static_cast<std::size_t>(a)]);
  }
  for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
    const Feature& f = features_[items_[k]];
    const double t = detail::segment_parameter(p, f.a, f.b);
    const double d = (p - (f.a + t * (f.b - f.a))).norm();
    if (d < best.distance) best = {d, f.curve, f.point, f.segment, t};
  }
  if (best.distance > reach_) best = Nearest{};
  return best;
}

}  // namespace zeroset
