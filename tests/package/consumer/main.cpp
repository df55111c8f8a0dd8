// Uses an installed zeroset: parses an equation, resolves a catalog surface, evaluates both,
// and meshes one (the mesh module brings OpenMP and fmt in at link time).
#include <cstdio>
#include <exception>

#include "zeroset/expr/parse.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/surface/catalog.h"

int main() {
  try {
    zeroset::Field sphere = zeroset::compile_field("x^2 + y^2 + z^2 = r^2");
    sphere.set_parameter("r", 2.0);
    zeroset::Evaluator ev(sphere);
    zeroset::Vec3 gradient;
    const double value = ev.value_gradient({1, 2, 3}, gradient);
    std::printf("equation F(1,2,3) = %.17g, grad F = %.17g %.17g %.17g\n", value, gradient.x(),
                gradient.y(), gradient.z());

    const zeroset::CatalogEntry* entry = zeroset::find_catalog_entry("cayley");
    if (entry == nullptr) {
      std::fprintf(stderr, "consumer: no catalog entry 'cayley'\n");
      return 1;
    }
    const zeroset::Surface cayley = zeroset::make_surface(*entry);
    zeroset::Evaluator cayley_ev(cayley.field);
    std::printf("cayley F(0.5,0.5,0.5) = %.17g\n", cayley_ev.value({0.5, 0.5, 0.5}));

    const zeroset::Mesh mesh = zeroset::polygonize(cayley, {.cells = 16});
    std::printf("cayley mesh: %zu triangles\n", mesh.triangles.size());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "consumer: %s\n", e.what());
    return 1;
  }
  return 0;
}
