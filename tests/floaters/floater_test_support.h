#pragma once
// Surfaces for the floater tests.
#include <map>
#include <string>

#include "zeroset/surface/scene.h"

namespace zeroset::test {

// A catalog surface with some parameters set, resolved the way the command line does it.
inline Surface catalog_surface(const char* name, std::map<std::string, double> params = {}) {
  SurfaceOverrides o;
  o.params = std::move(params);
  return resolve_surface(name, o);
}

}  // namespace zeroset::test
