// Ray casting: whole 800×800 pictures of the reference scenes (one ray per pixel, the
// settings of the peer comparison in render_peers.py), the PNG output, and the root finder
// on its own, with and without a guess.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "zeroset/io/image.h"
#include "zeroset/render/render.h"
#include "zeroset/render/roots.h"
#include "zeroset/surface/catalog.h"

namespace {

using namespace zeroset;

void render_scene(benchmark::State& state, const char* name, int threads) {
  const Surface surface = make_surface(*find_catalog_entry(name));
  RenderOptions o;
  o.width = o.height = 800;
  o.samples = 1;
  o.threads = threads;
  RenderStats stats;
  for (auto _ : state) benchmark::DoNotOptimize(render_surface(surface, o, &stats));
  state.counters["rays/s"] = benchmark::Counter(static_cast<double>(stats.rays),
                                                benchmark::Counter::kIsIterationInvariantRate);
  state.counters["hits"] = static_cast<double>(stats.hits);
}

int threads(const benchmark::State& s) { return static_cast<int>(s.range(0)); }
void BM_RenderKummer(benchmark::State& s) { render_scene(s, "kummer", threads(s)); }
void BM_RenderBarth(benchmark::State& s) { render_scene(s, "barth6", threads(s)); }
void BM_RenderRoman(benchmark::State& s) { render_scene(s, "roman", threads(s)); }
void BM_RenderCone(benchmark::State& s) { render_scene(s, "cone", threads(s)); }
void BM_RenderPlanes(benchmark::State& s) { render_scene(s, "planes", threads(s)); }
BENCHMARK(BM_RenderKummer)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderBarth)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderRoman)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderCone)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderPlanes)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

/// write_png of the 800×800 Kummer picture (compressed in bands on all cores).
void BM_WritePng(benchmark::State& state) {
  const Surface surface = make_surface(*find_catalog_entry("kummer"));
  RenderOptions o;
  o.width = o.height = 800;
  const Image image = render_surface(surface, o);
  const std::string path =
      (std::filesystem::temp_directory_path() / "zeroset_bench_render.png").string();
  for (auto _ : state) write_png(image, path);
  std::filesystem::remove(path);
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(image.rgb.size()));
}
BENCHMARK(BM_WritePng)->Unit(benchmark::kMillisecond)->UseRealTime();

/// 100,000 disks on the unit sphere (a Fibonacci lattice), as floaters are drawn.
void BM_RenderPoints(benchmark::State& state) {
  const Surface surface = make_surface(*find_catalog_entry("sphere"));
  const int n = 100000;
  std::vector<Vec3> p;
  const double golden = 3.14159265358979 * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z);
    p.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  const std::vector<double> radii(p.size(), 0.012);
  RenderOptions o;
  o.width = o.height = 800;
  o.threads = 2;
  for (auto _ : state) benchmark::DoNotOptimize(render_points(surface, p, p, radii, o));
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_RenderPoints)->Unit(benchmark::kMillisecond)->UseRealTime();

/// First root of random polynomials with real roots spread over the interval; with
/// range(1) = 1 the search is given a guess within 1e-3 of the first root (as a neighbouring
/// ray's hit gives it), and the spread 1e-2.
void BM_FirstRoot(benchmark::State& state) {
  const int degree = static_cast<int>(state.range(0));
  const bool guided = state.range(1) != 0;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-2, 6), nudge(-1e-3, 1e-3);
  struct Case {
    std::vector<double> coeffs;
    RootGuess guess;
  };
  std::vector<Case> cases;
  for (int n = 0; n < 256; ++n) {
    std::vector<double> c{1.0};
    double first = 1e300;
    for (int r = 0; r < degree; ++r) {
      const double root = u(rng);
      if (root >= 0 && root <= 4) first = std::min(first, root);
      std::vector<double> next(c.size() + 1, 0.0);
      for (size_t k = 0; k < c.size(); ++k) {
        next[k + 1] += c[k];
        next[k] -= root * c[k];
      }
      c = next;
    }
    Case k{c, {}};
    if (guided && first < 1e300) k.guess = {first + nudge(rng), 1e-2};
    cases.push_back(k);
  }
  RootFinder finder;
  size_t i = 0;
  for (auto _ : state) {
    const Case& k = cases[i++ % cases.size()];
    benchmark::DoNotOptimize(finder.first_root(k.coeffs, 0.0, 4.0, 1e-12, k.guess));
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["subdivisions/call"] =
      static_cast<double>(finder.stats().subdivisions) / static_cast<double>(finder.stats().calls);
}
BENCHMARK(BM_FirstRoot)->ArgsProduct({{4, 6, 12}, {0, 1}});

}  // namespace

BENCHMARK_MAIN();
