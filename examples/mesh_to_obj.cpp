// Meshes a catalog surface and writes it as a Wavefront OBJ file.
//   mesh_to_obj [SURFACE] [OUT.obj] [CELLS]      e.g. mesh_to_obj kummer kummer.obj 64
#include <cstdio>
#include <exception>
#include <string>

#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/mesh_io.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"
#include "zeroset/surface/scene.h"

int main(int argc, char** argv) {
  const std::string name = argc > 1 ? argv[1] : "kummer";
  const std::string out = argc > 2 ? argv[2] : "mesh.obj";
  const int cells = argc > 3 ? std::stoi(argv[3]) : 64;
  try {
    // A catalog name, an equation or a scene file; parameters keep their defaults here.
    const zeroset::Surface surface = zeroset::resolve_surface(name);
    zeroset::check_mesh_path(out);  // fail before the work, not after it

    zeroset::Mesh mesh = zeroset::polygonize(surface, {.cells = cells});
    const zeroset::ImproveStats st = zeroset::improve_mesh(mesh, surface);
    zeroset::write_mesh(mesh, out);

    const zeroset::MeshQuality q = zeroset::measure_quality(mesh, surface);
    std::printf("%s: %zu vertices, %zu triangles after %d improver steps\n", out.c_str(),
                q.vertices, q.triangles, st.steps);
    std::printf("triangles below 30 degrees: %.1f%%, max |F|/|grad F|: %.2g\n", q.percent_below_30,
                q.max_residual);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "mesh_to_obj: %s\n", e.what());
    return 1;
  }
  return 0;
}
