// Floaters on fields that are undefined on part of the clip or whose first-order distance
// misleads: they never leave the clip, never stay where F or ∇F is not finite, and settle on
// the surface whatever its degree.
#include <gtest/gtest.h>

#include <cmath>

#include "support/equation.h"
#include "zeroset/expr/field.h"
#include "zeroset/floaters/floaters.h"

namespace zeroset {
namespace {

using test::equation;

// sqrt(x) + y² + z² − 1 is NaN for x < 0: floaters that step there are removed, and after
// every step each floater lies where F and ∇F are finite, inside the clip.
TEST(FloatersNonFinite, StayWhereFIsDefinedAndInsideTheClip) {
  const Surface s = equation("sqrt(x) + y^2 + z^2 - 1", Clip::sphere(2));
  FloaterOptions o;
  o.max_count = 400;
  FloaterSystem sys(s, o);
  Evaluator ev(s.field);
  std::size_t undefined_removed = 0;
  for (int k = 0; k < 120; ++k) {
    const StepStats st = sys.step();
    undefined_removed += st.undefined_removed;
    EXPECT_LE(st.undefined_removed, st.removed);
    for (std::size_t i = 0; i < sys.size(); ++i) {
      const Vec3& p = sys.positions()[i];
      Vec3 g;
      ASSERT_TRUE(std::isfinite(ev.value_gradient(p, g)) && g.allFinite()) << p.transpose();
      ASSERT_TRUE(s.clip.contains(p, 1e-9)) << p.transpose();
      ASSERT_TRUE(std::isfinite(sys.radii()[i]));
    }
  }
  EXPECT_GT(sys.size(), 50u);
}

// F = 1/(x − x) − 1 is NaN everywhere: no floater survives a step (each is a stray).
TEST(FloatersNonFinite, AnUndefinedFieldKeepsNoFloater) {
  const Surface s = equation("1/(x - x) - 1", Clip::sphere(1));
  FloaterOptions o;
  o.max_count = 100;
  FloaterSystem sys(s, o);
  for (int k = 0; k < 5; ++k) {
    const StepStats st = sys.step();
    EXPECT_EQ(st.count, 0u);
    EXPECT_EQ(sys.size(), 0u);
    EXPECT_GT(st.removed, 0u);
  }
}

// (x² + y² + z²)^n − 1 for large n: |F|/|∇F| = r/(2n) wherever r > 1, so a first-order pull
// crawls and floaters settled by motion alone would sit off the sphere. They settle on it.
TEST(FloatersNonFinite, HighDegreeSphereFloatersSettleOnTheSphere) {
  for (const char* eq : {"(x^2 + y^2 + z^2)^1000 - 1", "(x^2 + y^2 + z^2)^50 - 1"}) {
    SCOPED_TRACE(eq);
    const Surface s = equation(eq, Clip::sphere(2));
    FloaterOptions o;
    o.max_count = 300;
    FloaterSystem sys(s, o);
    bool settled = false;
    for (int k = 0; k < 2000 && !settled; ++k) settled = sys.step().converged;
    ASSERT_TRUE(settled);
    ASSERT_GE(sys.size(), 10u);
    for (const Vec3& p : sys.positions()) ASSERT_NEAR(p.norm(), 1.0, 1e-3) << p.transpose();
  }
}

}  // namespace
}  // namespace zeroset
