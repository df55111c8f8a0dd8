// The improver's set-up: its options' rules, how many workers it takes and the mean edge
// length its thresholds scale with (docs/algorithms.md, the mesh improver); and improve_mesh,
// the improver run to rest through its public steps.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stop_token>
#include <utility>

#include <fmt/core.h>

#include "mesh_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/error.h"
#include "zeroset/mesh/improve.h"

namespace zeroset::detail {

void check_improve_options(const ImproveOptions& o) {
  auto bad = [](const char* name, double v, const char* why) {
    throw InvalidArgument(name, fmt::format("{}", v), why);
  };
  if (o.max_steps < 0) bad("max_steps", o.max_steps, "must be ≥ 0");
  if (!(o.relaxation > 0 && o.relaxation <= 1))
    bad("relaxation", o.relaxation, "must be in (0, 1]");
  if (!(o.inertia >= 0 && o.inertia < 1)) bad("inertia", o.inertia, "must be in [0, 1)");
  if (!(o.feedback >= 0 && o.feedback <= 1)) bad("feedback", o.feedback, "must be in [0, 1]");
  if (!(o.spring_base > 0 && std::isfinite(o.spring_base)))
    bad("spring_base", o.spring_base, "must be > 0");
  if (!(o.curvature_weight >= 0 && std::isfinite(o.curvature_weight)))
    bad("curvature_weight", o.curvature_weight, "must be ≥ 0");
  if (!(o.singularity_weight >= 0 && std::isfinite(o.singularity_weight)))
    bad("singularity_weight", o.singularity_weight, "must be ≥ 0");
  if (!(o.singularity_scale > 0)) bad("singularity_scale", o.singularity_scale, "must be > 0");
  if (o.flip_steps < 0) bad("flip_steps", o.flip_steps, "must be ≥ 0");
  if (o.singularity_interval < 1)
    bad("singularity_interval", o.singularity_interval, "must be ≥ 1");
  if (!(o.flip_max_dihedral_deg >= 0 && o.flip_max_dihedral_deg < 90))
    bad("flip_max_dihedral_deg", o.flip_max_dihedral_deg, "must be in [0, 90)");
  if (!(o.speed_threshold > 0)) bad("speed_threshold", o.speed_threshold, "must be > 0");
  if (!(o.max_move_fraction > 0 && o.max_move_fraction <= 1))
    bad("max_move_fraction", o.max_move_fraction, "must be in (0, 1]");
  if (!(o.min_area_fraction >= 0 && o.min_area_fraction < 1))
    bad("min_area_fraction", o.min_area_fraction, "must be in [0, 1)");
  if (o.threads < 0) bad("threads", o.threads, "must be ≥ 0");
}

// A step is a dozen short parallel loops over the vertices, about a millisecond each for
// 50 000 vertices on one core. On a busy machine a fork-join then costs more than it saves:
// a preempted worker holds up the others, which spin at the barrier and take the CPU from it
// (measured at 128³, 47 000 vertices, load ~5 on 2 cores: 7.3 s with one worker, 23.9 s with
// two, 10.8 s with two under OMP_WAIT_POLICY=passive). So with threads = 0 the improver uses
// one worker per kVerticesPerWorker vertices, at most all cores.
constexpr size_t kVerticesPerWorker = 100000;

int improver_workers(int requested, size_t vertices) {
  if (requested > 0) return detail::worker_count(requested);
  const size_t by_size = std::max<size_t>(1, vertices / kVerticesPerWorker);
  return static_cast<int>(std::min<size_t>(by_size, static_cast<size_t>(detail::worker_count(0))));
}

double improver_mean_edge(const std::vector<Vec3>& positions, const std::vector<std::uint32_t>& nbr,
                          const std::vector<std::uint32_t>& nbr_count, int cap, int workers) {
  // Sums per block of vertices, added in block order: the same rounding whatever the
  // number of workers (an OpenMP reduction would add in thread order).
  constexpr long long kBlock = 4096;
  const long long n = static_cast<long long>(positions.size());
  const long long blocks = (n + kBlock - 1) / kBlock;
  std::vector<double> block_sum(static_cast<size_t>(blocks), 0.0);
  std::vector<long long> block_count(static_cast<size_t>(blocks), 0);
  ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(static)
  for (long long b = 0; b < blocks; ++b)
    trap.run([&] {
      double sum = 0;
      long long count = 0;
      for (long long v = b * kBlock; v < std::min(n, (b + 1) * kBlock); ++v) {
        const std::uint32_t* q = &nbr[static_cast<size_t>(v) * static_cast<size_t>(cap)];
        for (std::uint32_t k = 0; k < nbr_count[static_cast<size_t>(v)]; ++k)
          if (q[k] > v) {
            sum += (positions[q[k]] - positions[static_cast<size_t>(v)]).norm();
            ++count;
          }
      }
      block_sum[static_cast<size_t>(b)] = sum;
      block_count[static_cast<size_t>(b)] = count;
    });
  trap.rethrow();
  double sum = 0;
  long long count = 0;
  for (long long b = 0; b < blocks; ++b)
    sum += block_sum[static_cast<size_t>(b)], count += block_count[static_cast<size_t>(b)];
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

}  // namespace zeroset::detail

namespace zeroset {

ImproveStats improve_mesh(Mesh& mesh, const Surface& surface, const ImproveOptions& options,
                          std::stop_token stop) {
  MeshImprover improver(std::move(mesh), surface, options);
  for (int i = 0; i < options.max_steps && !improver.converged() && !stop.stop_requested(); ++i)
    improver.step();
  if (options.final_projection && !stop.stop_requested()) improver.finish();
  ImproveStats st = improver.stats();
  mesh = improver.take_mesh();
  return st;
}

}  // namespace zeroset
