// Samples a surface with floaters while one of its parameters moves, and prints how well the
// floaters follow it.
//   floaters_animate [MAX_COUNT] [STEPS] [OUT.ply]      e.g. floaters_animate 2000 300 k.ply
#include <cstdio>
#include <exception>
#include <string>

#include "zeroset/floaters/ply.h"
#include "zeroset/floaters/sample_surface.h"
#include "zeroset/surface/scene.h"

int main(int argc, char** argv) {
  const std::size_t max_count = argc > 1 ? std::stoul(argv[1]) : 2000;
  const std::size_t steps = argc > 2 ? std::stoul(argv[2]) : 300;
  const std::string out = argc > 3 ? argv[3] : "floaters.ply";
  try {
    const zeroset::Surface surface = zeroset::resolve_surface("kummer");
    // The recipe of `zeroset sample --animate mu=1.5:2 --steps STEPS`: the floaters spread
    // over the surface at mu = 1.5 first, then each step passes the next value of mu, so they
    // follow the surface instead of having to find it again.
    zeroset::SampleRun run;
    run.animation = zeroset::SampleAnimation{
        .parameter = "mu", .from = 1.5, .to = 2.0, .steps = steps, .settle_steps = 2000};
    const std::size_t every = steps / 10 > 0 ? steps / 10 : 1;
    std::size_t animated = 0;
    run.on_step = [&](const zeroset::StepStats& st, double done) {
      if (done == 0) return;  // still settling
      if (++animated % every == 0)
        std::printf("mu = %.3f  floaters %5zu  median |F|/|grad F| %.2e  rms speed %.3f\n",
                    1.5 + 0.5 * done, st.count, st.median_residual, st.rms_speed);
    };
    const zeroset::SampleResult r =
        zeroset::sample_surface(surface, {.max_count = max_count, .seed = 7}, run);
    for (const std::string& warning : r.warnings) std::fprintf(stderr, "%s\n", warning.c_str());
    if (!r.system) return 1;
    std::printf("settled after %zu steps; %zu floaters at the end\n", r.animation->settle_steps,
                r.system->size());
    zeroset::write_points_ply(out, r.system->positions(), r.system->normals(), r.system->radii());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "floaters_animate: %s\n", e.what());
    return 1;
  }
  return 0;
}
