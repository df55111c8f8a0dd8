#pragma once
// Surfaces as the module tests make them: from an equation with a given clip, or from the
// catalog with its defaults.
#include <string>

#include "zeroset/surface/catalog.h"
#include "zeroset/surface/scene.h"

namespace zeroset::test {

inline Surface catalog_surface(const std::string& name) {
  return make_surface(*find_catalog_entry(name));
}

/// A SURFACE argument (catalog name, equation or scene file) resolved with a --clip spec.
inline Surface with_clip(const std::string& spec, const std::string& clip) {
  SurfaceOverrides o;
  o.clip_specs = {clip};
  return resolve_surface(spec, o);
}

inline Surface equation(const std::string& text, const Clip& clip) {
  Surface s = surface_from_equation(text);
  s.clip = clip;
  return s;
}

}  // namespace zeroset::test
