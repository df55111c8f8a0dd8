#include "zeroset/floaters/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "rng_detail.h"
#include "spatial_hash_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/surface/analysis.h"
#include "zeroset/surface/singular_index.h"

namespace zeroset {
namespace {

constexpr std::size_t kBlock = 16384;  // candidates per parallel round
constexpr std::size_t kChunk = 256;    // candidates per batched evaluation

}  // namespace

ReferenceSampling reference_sampling(const Surface& surface, const ReferenceOptions& options) {
  ReferenceSampling out;
  const Box3 box = surface.bounds();
  const double radius = surface.scene_radius();
  const double shell = options.shell > 0 ? options.shell : radius / 200;
  const std::size_t budget = options.max_candidates > 0
                                 ? options.max_candidates
                                 : 400 * std::max<std::size_t>(options.count, 1);
  const double tolerance = 1e-9 * radius;
  const int workers = detail::worker_count(0);
  detail::EvaluatorPool evs(surface.field, workers);
  std::size_t in_shell = 0;

  // Rounds of kBlock candidates: the stop token is looked at between them (a clip of many parts
  // makes each candidate costly).
  while (out.points.size() < options.count && out.candidates < budget &&
         !options.stop.stop_requested()) {
    const std::size_t base = out.candidates;
    const std::size_t m = std::min(kBlock, budget - base);
    const auto chunks = static_cast<std::int64_t>((m + kChunk - 1) / kChunk);
    std::vector<std::vector<Vec3>> found(static_cast<std::size_t>(chunks));
    std::vector<std::size_t> shell_hits(static_cast<std::size_t>(chunks), 0);
    detail::ExceptionTrap trap;
#pragma omp parallel for schedule(dynamic, 1) num_threads(workers)
    for (std::int64_t c = 0; c < chunks; ++c)
      trap.run([&] {
        Evaluator& ev = evs.local();
        const std::size_t b = static_cast<std::size_t>(c) * kChunk;
        const std::size_t e = std::min(m, b + kChunk);
        std::array<double, kChunk> x, y, z, f, gx, gy, gz;
        std::array<std::uint8_t, kChunk> inside{};
        for (std::size_t k = b; k < e; ++k) {
          detail::Rng rng(options.seed, base + k, 0, detail::Stream::kReference);
          const Vec3 p(rng.uniform(box.lo.x(), box.hi.x()), rng.uniform(box.lo.y(), box.hi.y()),
                       rng.uniform(box.lo.z(), box.hi.z()));
          x[k - b] = p.x();
          y[k - b] = p.y();
          z[k - b] = p.z();
          inside[k - b] = surface.clip.contains(p) ? 1 : 0;
        }
        const std::size_t len = e - b;
        ev.values_gradients({x.data(), len}, {y.data(), len}, {z.data(), len}, {f.data(), len},
                            {gx.data(), len}, {gy.data(), len}, {gz.data(), len});
        for (std::size_t k = 0; k < len; ++k) {
          if (!inside[k]) continue;
          const double g = std::sqrt(gx[k] * gx[k] + gy[k] * gy[k] + gz[k] * gz[k]);
          if (!std::isfinite(f[k]) || !(std::abs(f[k]) < shell * g)) continue;
          ++shell_hits[static_cast<std::size_t>(c)];
          Vec3 p(x[k], y[k], z[k]);
          if (project_onto_surface(ev, p, tolerance, 4 * shell) &&
              surface.clip.contains(p, tolerance))
            found[static_cast<std::size_t>(c)].push_back(p);
        }
      });
    trap.rethrow();
    // Appending in chunk order (and stopping at `count`) keeps the result thread-independent.
    for (std::size_t c = 0; c < found.size(); ++c) {
      in_shell += shell_hits[c];
      for (const Vec3& p : found[c])
        if (out.points.size() < options.count) out.points.push_back(p);
    }
    out.candidates += m;
  }
  const double box_volume = box.size().prod();
  out.area = out.candidates > 0 ? box_volume * static_cast<double>(in_shell) /
                                      static_cast<double>(out.candidates) / (2 * shell)
                                : 0;
  return out;
}

double estimate_area(const Surface& surface, std::uint64_t seed, std::stop_token stop) {
  ReferenceOptions o;
  o.count = 3000;
  o.seed = seed;
  o.stop = std::move(stop);
  o.max_candidates = 400'000;
  return reference_sampling(surface, o).area;
}

SampleMetrics measure_samples(const Surface& surface, std::span<const Vec3> samples,
                              const MetricsOptions& options) {
  SampleMetrics m;
  const std::size_t n = samples.size();
  m.count = n;
  const std::vector<Vec3> singular = surface.singular_points();
  const bool need_reference = options.covering || options.band_halfwidth > 0;
  if (n == 0 && !need_reference) return m;

  // Nearest-neighbour spacing through a grid of about two samples per occupied cell.
  Box3 box{Vec3::Constant(std::numeric_limits<double>::infinity()),
           Vec3::Constant(-std::numeric_limits<double>::infinity())};
  for (const Vec3& p : samples) {
    box.lo = box.lo.cwiseMin(p);
    box.hi = box.hi.cwiseMax(p);
  }
  if (n == 0) box = surface.bounds();
  const double extent = std::max(box.size().maxCoeff(), 1e-12);
  detail::SpatialHash grid;
  grid.build(samples, box,
             1.5 * extent / std::sqrt(static_cast<double>(std::max<std::size_t>(n, 1))));
  std::vector<double> nn(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const auto [j, d] = grid.nearest(samples[i], samples, static_cast<std::int64_t>(i));
    nn[i] = j >= 0 ? d : 0;
  }
  if (n >= 2) {
    double sum = 0, sq = 0;
    for (double d : nn) sum += d;
    m.spacing_mean = sum / static_cast<double>(n);
    for (double d : nn) sq += (d - m.spacing_mean) * (d - m.spacing_mean);
    m.spacing_cv = m.spacing_mean > 0 ? std::sqrt(sq / static_cast<double>(n)) / m.spacing_mean : 0;
  }

  // Residual, leaving out the balls around known singular points.
  Evaluator ev(surface.field);
  const double exclusion =
      options.singular_exclusion > 0 ? options.singular_exclusion : m.spacing_mean;
  std::vector<double> residuals;
  residuals.reserve(n);
  for (const Vec3& p : samples) {
    bool excluded = false;
    for (const Vec3& s : singular) excluded = excluded || (p - s).norm() < exclusion;
    if (excluded) {
      ++m.residual_excluded;
      continue;
    }
    Vec3 g;
    const double f = ev.value_gradient(p, g);
    residuals.push_back(residual(f, g.norm()));
  }
  if (!residuals.empty()) {
    const auto mid = residuals.begin() + static_cast<std::ptrdiff_t>(residuals.size() / 2);
    std::nth_element(residuals.begin(), mid, residuals.end());
    m.residual_median = *mid;
    m.residual_max = *std::max_element(residuals.begin(), residuals.end());
  }

  // Known singular points: distance to the nearest sample in units of the local spacing.
  if (n > 0) {
    for (const Vec3& s : singular) {
      SingularCoverage c;
      c.point = s;
      const auto near = grid.k_nearest(
          s, samples, static_cast<std::size_t>(std::max(1, options.local_neighbours)));
      c.distance = (samples[near.front()] - s).norm();
      double sum = 0;
      for (std::uint32_t j : near) sum += nn[j];
      c.local_spacing = sum / static_cast<double>(near.size());
      c.ratio = c.local_spacing > 0 ? c.distance / c.local_spacing : 0;
      m.singular_ratio_max = std::max(m.singular_ratio_max, c.ratio);
      m.singular.push_back(c);
    }
  }

  if (!need_reference) return m;
  const ReferenceSampling ref = reference_sampling(surface, options.reference);
  m.reference_count = ref.points.size();
  if (options.covering && n > 0) {
    for (const Vec3& q : ref.points)
      m.covering_radius = std::max(m.covering_radius, grid.nearest(q, samples, -1).second);
    m.covering_relative = m.spacing_mean > 0 ? m.covering_radius / m.spacing_mean : 0;
  } else if (options.covering && !ref.points.empty()) {
    m.covering_radius = 2 * surface.scene_radius();  // nothing sampled: the whole surface is a gap
  }

  if (options.band_halfwidth > 0) {
    auto in_band = [&](const Vec3& p) {
      const FieldSample s = ev.sample(p, Derivatives::kHessian);
      return singular_distance(s.gradient, s.hessian) < options.band_halfwidth;
    };
    std::size_t ref_in = 0, sample_in = 0;
    for (const Vec3& q : ref.points) ref_in += in_band(q) ? 1 : 0;
    for (const Vec3& p : samples) sample_in += in_band(p) ? 1 : 0;
    m.band_samples = sample_in;
    m.band_reference = ref_in;
    const std::size_t ref_out = ref.points.size() - ref_in, sample_out = n - sample_in;
    if (ref_in > 0 && ref_out > 0 && sample_out > 0)
      m.band_density_ratio = (static_cast<double>(sample_in) / static_cast<double>(ref_in)) /
                             (static_cast<double>(sample_out) / static_cast<double>(ref_out));
  }
  return m;
}

}  // namespace zeroset

namespace zeroset {

SingularSetCoverage measure_singular_coverage(const SingularSet& set, std::span<const Vec3> samples,
                                              int local_neighbours, double on_set) {
  SingularSetCoverage c;
  c.point_ratio.assign(set.points.size(), 0.0);
  c.curve_gap.assign(set.curves.size(), 0.0);
  if (samples.empty()) return c;
  Box3 box{samples[0], samples[0]};
  for (const Vec3& p : samples) {
    box.lo = box.lo.cwiseMin(p);
    box.hi = box.hi.cwiseMax(p);
  }
  const double extent = std::max(box.size().maxCoeff(), 1e-12);
  if (!(on_set > 0)) on_set = 1e-9 * extent;
  const SingularSetIndex index = set.empty() ? SingularSetIndex() : SingularSetIndex(set, on_set);
  std::vector<Vec3> off;
  for (const Vec3& p : samples)
    if (!(index.distance(p) <= on_set)) off.push_back(p);
  if (off.size() < 2) return c;
  auto grid_over = [&](std::span<const Vec3> points) {
    detail::SpatialHash grid;
    grid.build(points, box, 1.5 * extent / std::sqrt(static_cast<double>(points.size())));
    return grid;
  };
  const detail::SpatialHash all = grid_over(samples), sheets = grid_over(off);
  std::vector<double> nn(off.size());
  double mean = 0;
  for (std::size_t i = 0; i < off.size(); ++i) {
    nn[i] = sheets.nearest(off[i], off, static_cast<std::int64_t>(i)).second;
    mean += nn[i] / static_cast<double>(off.size());
  }
  const auto k = static_cast<std::size_t>(std::max(1, local_neighbours));
  auto spacing = [&](const Vec3& q) {
    double sum = 0;
    const auto near = sheets.k_nearest(q, off, k);
    for (std::uint32_t j : near) sum += nn[j];
    return sum / static_cast<double>(near.size());
  };
  auto ratio = [&](const Vec3& q) {
    const double s = spacing(q);
    return s > 0 ? all.nearest(q, samples, -1).second / s : 0.0;
  };
  for (std::size_t k2 = 0; k2 < set.points.size(); ++k2) {
    c.point_ratio[k2] = ratio(set.points[k2].position);
    c.point_ratio_max = std::max(c.point_ratio_max, c.point_ratio[k2]);
  }
  const double probe = 0.1 * mean;
  for (std::size_t k2 = 0; k2 < set.curves.size(); ++k2) {
    const auto& pts = set.curves[k2].points;
    double worst = pts.empty() ? 0.0 : ratio(pts[0]);
    for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
      const double len = (pts[i + 1] - pts[i]).norm();
      const int pieces = std::max(1, static_cast<int>(std::ceil(len / std::max(probe, 1e-300))));
      for (int j = 1; j <= pieces; ++j)
        worst = std::max(worst, ratio(pts[i] + (pts[i + 1] - pts[i]) * (double(j) / pieces)));
    }
    c.curve_gap[k2] = 2 * worst;
    c.curve_gap_max = std::max(c.curve_gap_max, c.curve_gap[k2]);
  }
  return c;
}

}  // namespace zeroset
