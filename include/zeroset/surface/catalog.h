#pragma once
/// The catalog of named surfaces with defaults (docs/architecture.md, "Modules").
#include <string>
#include <string_view>
#include <vector>

#include "zeroset/surface/surface.h"

namespace zeroset {

/// A catalog surface's parameter: its default value and slider range.
struct CatalogParam {
  std::string name;
  double value = 0;
  double min = 0;
  double max = 1;
};

struct CatalogEntry {
  std::string name;         ///< e.g. "kummer"
  std::string title;        ///< e.g. "Kummer quartic family (Rösch–Ruhl–Saupe 1997)"
  std::string equation;     ///< source in the surface language
  std::string description;  ///< one or two sentences, with what is known about its singularities
  std::vector<CatalogParam> params;
  Clip clip;
  Camera camera;
  SingularPointsFn singular_points;  ///< empty when none are known
};

/// Every catalog entry, in a fixed order.
const std::vector<CatalogEntry>& catalog();
/// The entry with that name, or nullptr.
const CatalogEntry* find_catalog_entry(std::string_view name);
/// A compiled surface with the entry's defaults.
Surface make_surface(const CatalogEntry& entry);

}  // namespace zeroset
