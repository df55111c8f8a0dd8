#include "zeroset/expr/interval.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "surfaces.h"
#include "zeroset/error.h"
#include "zeroset/expr/parse.h"

namespace zeroset {
namespace {

bool encloses(const Interval& e, double v) { return !std::isfinite(v) || (e.lo <= v && v <= e.hi); }

// F and ∇F at points of a box lie in the box's enclosures, for every operation of the tape.
TEST(IntervalEvaluator, EnclosesTheFieldAndItsGradientOverABox) {
  std::vector<test::Surface> surfaces = test::polynomial_surfaces();
  for (const auto& s : test::transcendental_surfaces()) surfaces.push_back(s);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (const test::Surface& s : surfaces) {
    SCOPED_TRACE(s.source);
    const Field field = test::compile(s);
    IntervalEvaluator intervals(field);
    Evaluator points(field);
    for (const Vec3& corner : test::random_points(40, 1.4, 3)) {
      const Vec3 size(0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng));
      const Interval x{corner.x(), corner.x() + size.x()}, y{corner.y(), corner.y() + size.y()},
          z{corner.z(), corner.z() + size.z()};
      const Interval value = intervals.eval(x, y, z);
      Interval e[4];
      intervals.eval_gradient(x, y, z, e);
      for (int i = 0; i < 20; ++i) {
        const Vec3 p = corner + Vec3(u(rng), u(rng), u(rng)).cwiseProduct(size);
        Vec3 g;
        const double v = points.value_gradient(p, g);
        EXPECT_TRUE(encloses(value, v)) << v << " at " << p.transpose();
        EXPECT_TRUE(encloses(e[0], v));
        for (int k = 0; k < 3; ++k) EXPECT_TRUE(encloses(e[k + 1], g[k])) << "axis " << k;
      }
    }
  }
}

// A point box gives a tight enclosure of the value there.
TEST(IntervalEvaluator, PointBoxesGiveTightEnclosures) {
  const Field field = compile_field("x^2 + y*z - 1");
  IntervalEvaluator intervals(field);
  const Interval e = intervals.eval({0.5, 0.5}, {2, 2}, {-0.25, -0.25});
  EXPECT_LE(e.lo, -1.25);
  EXPECT_GE(e.hi, -1.25);
  EXPECT_LT(e.hi - e.lo, 1e-12);
}

// Where F is undefined over the whole box, the enclosure is empty.
TEST(IntervalEvaluator, UndefinedOverTheBoxIsEmpty) {
  IntervalEvaluator intervals(compile_field("sqrt(x) - 1"));
  EXPECT_TRUE(intervals.eval({-2, -1}, {0, 1}, {0, 1}).is_empty());
  EXPECT_FALSE(intervals.eval({-1, 4}, {0, 1}, {0, 1}).is_empty());
}

TEST(IntervalEvaluator, RequiresParameterValues) {
  EXPECT_THROW(IntervalEvaluator(compile_field("x^2 - a")), InvalidArgument);
}

}  // namespace
}  // namespace zeroset
