#pragma once
// A surface from an equation with a given clip, as the module tests make them.
#include <string>

#include "zeroset/surface/scene.h"

namespace zeroset::test {

inline Surface equation(const std::string& text, const Clip& clip) {
  Surface s = surface_from_equation(text);
  s.clip = clip;
  return s;
}

}  // namespace zeroset::test
