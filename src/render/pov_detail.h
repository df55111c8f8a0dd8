#pragma once
// The pieces of a POV-Ray scene that the still export and the animation write alike.
#include <string>
#include <utility>
#include <vector>

#include "zeroset/render/render.h"

namespace zeroset::detail {

/// A number of the scene with every digit of a double. Throws BadInput when it is not finite:
/// POV-Ray cannot parse nan or inf, and a scene with them would be written for nothing.
std::string pov_number(double v);
/// <x, y, z> with every digit of a double (pov_number's check for each).
std::string pov_vec(const Vec3& v);
/// The #version line, global settings and the background.
std::string pov_preamble(const RenderOptions& options);
/// One term of the polynomial object: exponents of x, y, z and the coefficient as POV-Ray
/// text (a number, or an expression of declared variables).
struct PovTerm {
  int i = 0, j = 0, k = 0;
  std::string coefficient;
};
/// The `polynomial` object of `degree` with `terms`, `sturm`, clipped by the surface's clip
/// volume, with the front texture and the back one as interior_texture.
std::string pov_polynomial_object(int degree, const std::vector<PovTerm>& terms,
                                  const Surface& surface, const RenderOptions& options);
/// The polynomial of `surface` (its current parameter values), checked for POV-Ray: throws
/// BadInput when F is not a polynomial, above POV-Ray's degree 35, constant, has a
/// coefficient that is not finite (named with its term: 0 divided by 0, the square root of a
/// negative constant, an overflow of huge parameter values), or the clip is unbounded.
Polynomial pov_polynomial(const Surface& surface);

}  // namespace zeroset::detail
