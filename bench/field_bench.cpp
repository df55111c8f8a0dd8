// Throughput of the compiled field against hand-written C++ for the same surface.
//
// The compiled Kummer quartic (values_gradients over batches of points) is compared with a
// function written out by hand, value and analytic gradient, as one would write it for a
// single surface. Their ratio says what the generality of the language costs.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "zeroset/expr/parse.h"
#include "zeroset/expr/polynomial.h"

namespace {

constexpr const char* kKummer =
    "p = 1-z-sqrt(2)*x; q = 1-z+sqrt(2)*x; r = 1+z+sqrt(2)*y; s = 1+z-sqrt(2)*y; "
    "(3-mu)*(x^2+y^2+z^2-mu)^2 - (3*mu-1)*p*q*r*s";
constexpr const char* kBarth =
    "4*(phi^2*x^2-y^2)*(phi^2*y^2-z^2)*(phi^2*z^2-x^2) - (1+2*phi)*(x^2+y^2+z^2-1)^2";
constexpr double kMu = 1.5;
constexpr int kPoints = 4096;

/// Kummer's quartic by hand: p·q = (1-z)² - 2x² and r·s = (1+z)² - 2y².
inline double kummer_value_gradient(double x, double y, double z, double mu, double& gx, double& gy,
                                    double& gz) {
  const double s = x * x + y * y + z * z - mu;
  const double a = 3 - mu;
  const double b = 3 * mu - 1;
  const double pq = (1 - z) * (1 - z) - 2 * x * x;
  const double rs = (1 + z) * (1 + z) - 2 * y * y;
  gx = 4 * a * s * x + 4 * b * x * rs;
  gy = 4 * a * s * y + 4 * b * y * pq;
  gz = 4 * a * s * z - b * (-2 * (1 - z) * rs + 2 * (1 + z) * pq);
  return a * s * s - b * pq * rs;
}

struct Batch {
  std::vector<double> x, y, z, value, gx, gy, gz;
  explicit Batch(int n) : value(n), gx(n), gy(n), gz(n) {
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> u(-3, 3);
    for (int i = 0; i < n; ++i) {
      x.push_back(u(rng));
      y.push_back(u(rng));
      z.push_back(u(rng));
    }
  }
};

zeroset::Field field(const char* source, const char* param, double value) {
  zeroset::Field f = zeroset::compile_field(source);
  f.set_parameter(param, value);
  return f;
}

/// True when the hand-written function agrees with the compiled field on the batch.
bool hand_written_agrees(Batch& b) {
  zeroset::Evaluator ev(field(kKummer, "mu", kMu));
  ev.values_gradients(b.x, b.y, b.z, b.value, b.gx, b.gy, b.gz);
  for (std::size_t i = 0; i < b.x.size(); ++i) {
    double g[3];
    const double v = kummer_value_gradient(b.x[i], b.y[i], b.z[i], kMu, g[0], g[1], g[2]);
    const double scale =
        std::max({1.0, std::abs(v), std::abs(g[0]), std::abs(g[1]), std::abs(g[2])});
    if (std::abs(v - b.value[i]) > 1e-12 * scale || std::abs(g[0] - b.gx[i]) > 1e-12 * scale ||
        std::abs(g[1] - b.gy[i]) > 1e-12 * scale || std::abs(g[2] - b.gz[i]) > 1e-12 * scale)
      return false;
  }
  return true;
}

void BM_KummerValueGradientCompiled(benchmark::State& state) {
  Batch b(kPoints);
  zeroset::Evaluator ev(field(kKummer, "mu", kMu));
  for (auto _ : state) {
    ev.values_gradients(b.x, b.y, b.z, b.value, b.gx, b.gy, b.gz);
    benchmark::DoNotOptimize(b.value.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}
BENCHMARK(BM_KummerValueGradientCompiled);

void BM_KummerValueGradientHandWritten(benchmark::State& state) {
  Batch b(kPoints);
  if (!hand_written_agrees(b)) {
    state.SkipWithError("the hand-written Kummer function disagrees with the compiled field");
    return;
  }
  double mu = kMu;
  for (auto _ : state) {
    benchmark::DoNotOptimize(mu);  // a run-time parameter, as for the compiled field
    for (int i = 0; i < kPoints; ++i)
      b.value[i] = kummer_value_gradient(b.x[i], b.y[i], b.z[i], mu, b.gx[i], b.gy[i], b.gz[i]);
    benchmark::DoNotOptimize(b.value.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}
BENCHMARK(BM_KummerValueGradientHandWritten);

void BM_KummerValuesCompiled(benchmark::State& state) {
  Batch b(kPoints);
  zeroset::Evaluator ev(field(kKummer, "mu", kMu));
  for (auto _ : state) {
    ev.values(b.x, b.y, b.z, b.value);
    benchmark::DoNotOptimize(b.value.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}
BENCHMARK(BM_KummerValuesCompiled);

// The same calls over 10^6 points at once, which stream from memory instead of staying in
// cache: the reference for evaluating a large array from Python (bench/python_overhead.py).
constexpr int kMillion = 1'000'000;

void BM_KummerValuesCompiledMillion(benchmark::State& state) {
  Batch b(kMillion);
  zeroset::Evaluator ev(field(kKummer, "mu", kMu));
  for (auto _ : state) {
    ev.values(b.x, b.y, b.z, b.value);
    benchmark::DoNotOptimize(b.value.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * kMillion);
}
BENCHMARK(BM_KummerValuesCompiledMillion);

void BM_KummerValueGradientCompiledMillion(benchmark::State& state) {
  Batch b(kMillion);
  zeroset::Evaluator ev(field(kKummer, "mu", kMu));
  for (auto _ : state) {
    ev.values_gradients(b.x, b.y, b.z, b.value, b.gx, b.gy, b.gz);
    benchmark::DoNotOptimize(b.value.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * kMillion);
}
BENCHMARK(BM_KummerValueGradientCompiledMillion);

void BM_BarthValueGradientCompiled(benchmark::State& state) {
  Batch b(kPoints);
  zeroset::Evaluator ev(field(kBarth, "phi", std::numbers::phi));
  for (auto _ : state) {
    ev.values_gradients(b.x, b.y, b.z, b.value, b.gx, b.gy, b.gz);
    benchmark::DoNotOptimize(b.value.data());
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}
BENCHMARK(BM_BarthValueGradientCompiled);

/// One point at a time with everything: value, gradient, Hessian and ∂F/∂mu.
void BM_KummerSampleScalar(benchmark::State& state) {
  Batch b(kPoints);
  zeroset::Evaluator ev(field(kKummer, "mu", kMu));
  int i = 0;
  for (auto _ : state) {
    const zeroset::FieldSample s = ev.sample({b.x[i], b.y[i], b.z[i]});
    benchmark::DoNotOptimize(s.value);
    i = (i + 1) % kPoints;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_KummerSampleScalar);

/// One point at a time, value and gradient (the floaters' per-particle call).
void BM_KummerValueGradientScalar(benchmark::State& state) {
  Batch b(kPoints);
  zeroset::Evaluator ev(field(kKummer, "mu", kMu));
  int i = 0;
  for (auto _ : state) {
    zeroset::Vec3 g;
    benchmark::DoNotOptimize(ev.value_gradient({b.x[i], b.y[i], b.z[i]}, g));
    i = (i + 1) % kPoints;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_KummerValueGradientScalar);

void BM_BarthPolynomialExpansion(benchmark::State& state) {
  const zeroset::Field f = field(kBarth, "phi", std::numbers::phi);
  for (auto _ : state) benchmark::DoNotOptimize(f.polynomial());
}
BENCHMARK(BM_BarthPolynomialExpansion);

void BM_KummerRestrictToLine(benchmark::State& state) {
  const zeroset::Polynomial p = field(kKummer, "mu", kMu).polynomial();
  Batch b(kPoints);
  double out[5];
  int i = 0;
  for (auto _ : state) {
    p.restrict_to_line({b.x[i], b.y[i], b.z[i]}, {0.6, 0.0, 0.8}, out);
    benchmark::DoNotOptimize(out);
    i = (i + 1) % kPoints;
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_KummerRestrictToLine);

}  // namespace
