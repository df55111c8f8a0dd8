// Samples a surface with floaters while one of its parameters moves, and prints how well the
// floaters follow it.
//   floaters_animate [MAX_COUNT] [STEPS] [OUT.ply]      e.g. floaters_animate 2000 300 k.ply
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "zeroset/floaters/floaters.h"
#include "zeroset/floaters/ply.h"
#include "zeroset/surface/scene.h"

int main(int argc, char** argv) {
  const std::size_t max_count = argc > 1 ? std::stoul(argv[1]) : 2000;
  const int steps = argc > 2 ? std::stoi(argv[2]) : 300;
  const std::string out = argc > 3 ? argv[3] : "floaters.ply";
  try {
    const zeroset::Surface surface = zeroset::resolve_surface("kummer", {.params = {{"mu", 1.5}}});
    zeroset::FloaterSystem sys(surface, {.max_count = max_count, .seed = 7});

    // Let the floaters spread over the surface first.
    int settle = 0;
    while (settle < 2000 && !sys.step().converged) ++settle;
    std::printf("settled after %d steps with %zu floaters\n", settle, sys.size());

    // Then move mu from 1.5 to 2.0: each step passes the next value, so the floaters follow
    // the surface instead of having to find it again.
    std::vector<double> q(sys.parameters().begin(), sys.parameters().end());
    const int mu = surface.field.parameter_index("mu");
    for (int i = 1; i <= steps; ++i) {
      q[static_cast<std::size_t>(mu)] = 1.5 + 0.5 * i / steps;
      const zeroset::StepStats st = sys.step(q);
      if (i % (steps / 10 > 0 ? steps / 10 : 1) == 0)
        std::printf("mu = %.3f  floaters %5zu  median |F|/|grad F| %.2e  rms speed %.3f\n",
                    q[static_cast<std::size_t>(mu)], st.count, st.median_residual, st.rms_speed);
    }
    zeroset::write_points_ply(out, sys.positions(), sys.normals(), sys.radii());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "floaters_animate: %s\n", e.what());
    return 1;
  }
  return 0;
}
