#pragma once
// Surfaces for the mesh tests.
#include <string>

#include "support/equation.h"
#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset::test {

inline Surface kummer(double mu, double clip_radius = 3) {
  Surface s = catalog_surface("kummer");
  s.field.set_parameter("mu", mu);
  s.clip = Clip::sphere(clip_radius);
  return s;
}

}  // namespace zeroset::test
