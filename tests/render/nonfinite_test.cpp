// The ray tracer and the POV-Ray export where F is undefined or its coefficients are not
// finite: bounded work per ray, counted give-ups, no exact path on overflowed coefficients, and
// refused exports.
#include <gtest/gtest.h>

#include <cmath>

#include "support/equation.h"
#include "zeroset/error.h"
#include "zeroset/render/pov_export.h"
#include "zeroset/render/raycast.h"
#include "zeroset/render/render.h"

namespace zeroset {
namespace {

using test::equation;

// NaN everywhere: intervals exclude nothing, so each ray would visit every leaf of its
// subdivision. The budget ends it as a counted miss.
TEST(RaycastNonFinite, AnUndefinedFieldCostsABoundedBudgetPerRay) {
  const Surface s = equation("1/(x - x) - 1", Clip::sphere(2));
  SurfaceRayCaster caster(s, Vec3(0, 0, 6));
  for (int k = 0; k < 20; ++k) EXPECT_FALSE(caster.first_hit(Vec3(0.01 * k, 0.02, -1)).has_value());
  EXPECT_EQ(caster.abandoned_rays(), 20);
  RenderOptions o;
  o.width = o.height = 48;
  o.threads = 1;
  RenderStats st;
  render_surface(s, o, &st);
  EXPECT_GT(st.abandoned_rays, 0);
  EXPECT_EQ(st.hits, 0);
}

// F ≡ 0 is no surface, whichever path casts the rays: no hit, the picture is the background
// (interval arithmetic alone would find F = 0 on every ray and draw the clip).
TEST(RaycastNonFinite, AVanishingFieldShowsNoSurface) {
  for (const char* eq : {"sin(x) - sin(x)", "0*exp(x)", "x - x"}) {
    SCOPED_TRACE(eq);
    const Surface s = equation(eq, Clip::sphere(2));
    RenderOptions o;
    o.width = o.height = 32;
    o.threads = 1;
    RenderStats st;
    const Image image = render_surface(s, o, &st);
    EXPECT_EQ(st.hits, 0);
    EXPECT_GT(st.rays, 0);
    const Image blank = render_surface(equation("x^2 + y^2 + z^2 + 1", Clip::sphere(2)), o);
    ASSERT_EQ(image.rgb.size(), blank.rgb.size());
    for (int y = 0; y < image.height; ++y)
      for (int x = 0; x < image.width; ++x)
        for (int c = 0; c < 3; ++c) ASSERT_EQ(image.pixel(x, y)[c], blank.pixel(x, y)[c]);
  }
}

// A field defined along every ray needs far less than the budget: nothing is given up.
TEST(RaycastNonFinite, DefinedFieldsGiveUpNoRay) {
  for (const char* eq :
       {"sin(3*x) + sin(3*y) + sin(3*z)", "sqrt(x^2 + y^2 + 0.01) - 0.5 - z^2", "1/x - 1"}) {
    SCOPED_TRACE(eq);
    const Surface s = equation(eq, Clip::sphere(2));
    RenderOptions o;
    o.width = o.height = 64;
    o.threads = 1;
    RenderStats st;
    render_surface(s, o, &st);
    EXPECT_GT(st.hits, 0);
    EXPECT_EQ(st.abandoned_rays, 0);
  }
}

// A polynomial whose coefficients overflowed has no exact restriction to a ray: interval path.
TEST(RaycastNonFinite, OverflowedCoefficientsLeaveTheExactPath) {
  Surface s = equation("m^4*x^2 + y^2 + z^2 - 1", Clip::sphere(2));
  s.field.set_parameter("m", 1e100);
  SurfaceRayCaster caster(s, Vec3(0, 0, 6));
  EXPECT_FALSE(caster.is_exact());
  s.field.set_parameter("m", 1);
  EXPECT_TRUE(SurfaceRayCaster(s, Vec3(0, 0, 6)).is_exact());
}

// Every number of an exported scene is finite, or the export is refused.
TEST(PovExportNonFinite, NonFiniteCoefficientsAreRefused) {
  for (const char* eq : {"x/0 + y", "sqrt(-1) + x", "0/0*x^2 + y"}) {
    SCOPED_TRACE(eq);
    const Surface s = equation(eq, Clip::sphere(2));
    EXPECT_THROW(pov_scene(s, RenderOptions{}), BadInput);
  }
  Surface s = equation("m^4*x^2 + y^2 + z^2 - 1", Clip::sphere(2));
  s.field.set_parameter("m", 1e100);
  try {
    pov_scene(s, RenderOptions{});
    ADD_FAILURE() << "exported an infinite coefficient";
  } catch (const BadInput& e) {
    EXPECT_NE(std::string(e.what()).find("coefficient of x^2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace zeroset
