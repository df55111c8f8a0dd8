// Polygonizer and improver timings on the Kummer surface (mu = 1.5, grid over [-3, 3]^3, clip
// sphere R = 3), the reference scene of docs/benchmarks.md. Field sampling and extraction
// are reported as separate counters (milliseconds per run) from PolygonizeStats.
// Peers run beside it in bench/mesh_peers.py.
#include <benchmark/benchmark.h>

#include "zeroset/mesh/crossings.h"
#include "zeroset/mesh/improve.h"
#include "zeroset/mesh/mesh_surface.h"
#include "zeroset/mesh/polygonize.h"
#include "zeroset/mesh/quality.h"
#include "zeroset/mesh/remesh.h"
#include "zeroset/surface/catalog.h"

namespace {

zeroset::Surface kummer(double mu = 1.5) {
  zeroset::Surface s = zeroset::make_surface(*zeroset::find_catalog_entry("kummer"));
  s.field.set_parameter("mu", mu);
  s.clip = zeroset::Clip::sphere(3);
  return s;
}

// args: cells, grid mode (0 dense, 1 sparse), refine steps, polynomial rows (0/1)
void BM_Polygonize(benchmark::State& state) {
  const zeroset::Surface s = kummer();
  zeroset::PolygonizeOptions o;
  o.cells = static_cast<int>(state.range(0));
  o.mode = state.range(1) ? zeroset::GridMode::kSparse : zeroset::GridMode::kDense;
  o.refine_steps = static_cast<int>(state.range(2));
  o.polynomial_rows = state.range(3) != 0;
  double sampling = 0, extraction = 0, refinement = 0, cleanup = 0;
  size_t vertices = 0, triangles = 0;
  for (auto _ : state) {
    zeroset::PolygonizeStats st;
    const zeroset::Mesh m = zeroset::polygonize(s, o, &st);
    benchmark::DoNotOptimize(m.positions.data());
    sampling += st.seconds_sampling;
    extraction += st.seconds_extraction;
    refinement += st.seconds_refinement;
    cleanup += st.seconds_cleanup;
    vertices = m.vertex_count();
    triangles = m.triangle_count();
  }
  const double n = static_cast<double>(state.iterations());
  state.counters["sampling_ms"] = 1e3 * sampling / n;
  state.counters["extraction_ms"] = 1e3 * extraction / n;
  state.counters["refinement_ms"] = 1e3 * refinement / n;
  state.counters["cleanup_ms"] = 1e3 * cleanup / n;
  state.counters["vertices"] = static_cast<double>(vertices);
  state.counters["triangles"] = static_cast<double>(triangles);
}
BENCHMARK(BM_Polygonize)
    ->ArgNames({"cells", "sparse", "refine", "polyrows"})
    ->Args({64, 0, 12, 1})
    ->Args({128, 0, 12, 1})
    ->Args({256, 0, 12, 1})
    ->Args({64, 0, 0, 1})
    ->Args({128, 0, 0, 1})
    ->Args({256, 0, 0, 1})
    ->Args({256, 0, 12, 0})
    ->Args({256, 1, 12, 1})
    ->Args({512, 1, 12, 1})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// The improver on the 128³ mesh, run to convergence, with the quality it reaches.
void BM_Improve(benchmark::State& state) {
  const zeroset::Surface s = kummer();
  zeroset::PolygonizeOptions o;
  o.cells = static_cast<int>(state.range(0));
  const zeroset::Mesh start = zeroset::polygonize(s, o);
  zeroset::ImproveStats st;
  zeroset::Mesh m;
  for (auto _ : state) {
    m = start;
    st = zeroset::improve_mesh(m, s);
  }
  const zeroset::MeshQuality q = zeroset::measure_quality(m, s);
  state.counters["steps"] = st.steps;
  state.counters["pct_below_30"] = q.percent_below_30;
  state.counters["mean_min_angle"] = q.mean_min_angle_deg;
  state.counters["max_residual"] = q.max_residual;
}
BENCHMARK(BM_Improve)->Arg(128)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

// The whole mesh command's work (mesh_surface: marching cubes, crossings, improver to rest or
// its limit) on
// Kummer's surface with 16 nodes (mu = 1.5) and as four planes crossing in six lines and four
// triple points (mu = 3): what a surface with singular curves costs next to one with nodes.
// bench/crossings_report.py runs both side by side. args: 10 × mu; 1 for the remesher (the
// default improver), 0 for the paper's improver.
void BM_MeshPipeline(benchmark::State& state) {
  const zeroset::Surface s = kummer(static_cast<double>(state.range(0)) / 10);
  zeroset::MeshSettings settings;
  settings.cells = 128;
  settings.improver = state.range(1) != 0 ? zeroset::Improver::kRemesh : zeroset::Improver::kPaper;
  zeroset::MeshResult r;
  for (auto _ : state) r = zeroset::mesh_surface(s, settings);
  const zeroset::ImproveStats st =
      r.improvement ? r.improvement->summary() : zeroset::ImproveStats{};
  state.counters["steps"] = st.steps;
  state.counters["converged"] = st.converged;
  state.counters["vertices"] = static_cast<double>(r.mesh.vertex_count());
  state.counters["crossing_curves"] = r.crossings ? r.crossings->crossing_curves : 0;
  state.counters["crossings_ms"] = r.crossings ? 1e3 * r.crossings->seconds : 0;
}
BENCHMARK(BM_MeshPipeline)
    ->ArgNames({"mu10", "remesh"})
    ->ArgsProduct({{15, 30}, {1, 0}})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
