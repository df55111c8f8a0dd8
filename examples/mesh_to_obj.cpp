// Meshes a catalog surface and writes it as a Wavefront OBJ file.
//   mesh_to_obj [SURFACE] [OUT.obj] [CELLS]      e.g. mesh_to_obj kummer kummer.obj 64
#include <cstdio>
#include <exception>
#include <string>

#include "zeroset/mesh/mesh_io.h"
#include "zeroset/mesh/mesh_surface.h"
#include "zeroset/surface/scene.h"

int main(int argc, char** argv) {
  const std::string name = argc > 1 ? argv[1] : "kummer";
  const std::string out = argc > 2 ? argv[2] : "mesh.obj";
  const int cells = argc > 3 ? std::stoi(argv[3]) : 64;
  try {
    // A catalog name, an equation or a scene file; parameters keep their defaults here.
    const zeroset::Surface surface = zeroset::resolve_surface(name);
    zeroset::check_mesh_path(out);  // fail before the work, not after it

    // The recipe of `zeroset mesh`: marching cubes, crossings, the remesher, checks.
    zeroset::MeshSettings settings;
    settings.cells = cells;
    const zeroset::MeshResult r = zeroset::mesh_surface(surface, settings, {.quality = true});
    for (const std::string& warning : r.warnings) std::fprintf(stderr, "%s\n", warning.c_str());
    zeroset::write_mesh(r.mesh, out);

    const zeroset::MeshQuality& q = *r.quality_after;
    std::printf("%s: %zu vertices, %zu triangles after %d remesher iterations\n", out.c_str(),
                q.vertices, q.triangles, r.improvement ? r.improvement->summary().steps : 0);
    std::printf("triangles below 30 degrees: %.1f%%, max |F|/|grad F|: %.2g\n", q.percent_below_30,
                q.max_residual);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mesh_to_obj: %s\n", e.what());
    return 1;
  }
  return 0;
}
