#pragma once
/// Fast nearest-feature queries on a SingularSet for per-point use (every floater, every few
/// steps): a uniform grid whose cells list the curve segments and points that can be nearest to
/// a point of the cell within a bounded reach. SingularSet::distance is the plain loop over
/// everything; this answers the same question (within the reach) in time that depends on the
/// set's local density only.
#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "zeroset/surface/singular_set.h"
#include "zeroset/types.h"

namespace zeroset {

class SingularSetIndex {
 public:
  /// The nearest feature of the set: a point (`point` ≥ 0) or segment `segment` of curve
  /// `curve`, its nearest point at parameter t ∈ [0, 1] from the segment's first vertex.
  struct Nearest {
    double distance = std::numeric_limits<double>::infinity();  ///< infinity: none within reach
    int curve = -1;
    int point = -1;
    std::uint32_t segment = 0;
    double t = 0;
  };

  SingularSetIndex() = default;
  /// Indexes `set` for queries up to `reach` (> 0) from it. O(features · (reach/cell)³).
  SingularSetIndex(const SingularSet& set, double reach);

  /// The nearest point or curve of the set when it lies within the reach.
  Nearest nearest(const Vec3& p) const;
  /// Its distance: SingularSet::distance(p) when that is at most the reach, else infinity.
  double distance(const Vec3& p) const { return nearest(p).distance; }
  double reach() const { return reach_; }
  bool empty() const { return features_.empty(); }

 private:
  struct Feature {
    Vec3 a, b;
    int curve, point;
    std::uint32_t segment;
  };
  std::vector<Feature> features_;
  double reach_ = 0;
  double cell_ = 1;
  Vec3 origin_ = Vec3::Zero();
  std::array<int, 3> cells_{0, 0, 0};
  std::vector<std::uint32_t> start_;  // features of cell c: items_[start_[c], start_[c + 1])
  std::vector<std::uint32_t> items_;
};

}  // namespace zeroset
