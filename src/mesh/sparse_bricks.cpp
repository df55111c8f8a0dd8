// The polygonizer's sparse path: bricks near the surface; vertices identified by a global
// edge key.
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

#include <fmt/core.h>

#include "polygonize_detail.h"
#include "row_sampling_detail.h"
#include "vertex_placement_detail.h"
#include "zeroset/detail/bracket.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/error.h"

namespace zeroset::detail {
namespace {

struct KeyedCrossing {
  std::uint64_t key;
  Crossing c;
};

}  // namespace

ExtractedMesh extract_sparse(const Surface& surface, const Grid& g, const PolygonizeOptions& o,
                             const Polynomial* poly, int workers, PolygonizeStats& st,
                             const std::stop_token& stop) {
  ExtractedMesh res;
  const long long B = o.brick_cells;
  const std::array<long long, 3> nb = {(g.cells[0] + B - 1) / B, (g.cells[1] + B - 1) / B,
                                       (g.cells[2] + B - 1) / B};
  const long long bricks = nb[0] * nb[1] * nb[2];
  st.bricks += bricks;
  auto t0 = Clock::now();
  auto corner_index = [&](int a, long long b) { return std::min(b * B, g.cells[a]); };

  // Coarse test: F at brick corners (a lattice shared by neighbours) and F, ∇F at centres.
  const std::array<long long, 3> nc = {nb[0] + 1, nb[1] + 1, nb[2] + 1};
  std::vector<double> corner_value(static_cast<size_t>(nc[0] * nc[1] * nc[2]));
  std::vector<double> centre_value(static_cast<size_t>(bricks)), centre_slope(centre_value.size());
  EvaluatorPool pool(surface.field, workers);
  ExceptionTrap trap;
#pragma omp parallel num_threads(workers)
  {
    std::vector<double> x, y, z, f, gx, gy, gz;
    Evaluator& ev = pool.local();
#pragma omp for schedule(static)
    for (long long r = 0; r < nc[1] * nc[2]; ++r)
      trap.run([&] {
        const long long bj = r % nc[1], bk = r / nc[1];
        const size_t n = static_cast<size_t>(nc[0]);
        x.resize(n), y.assign(n, g.coord(1, corner_index(1, bj))),
            z.assign(n, g.coord(2, corner_index(2, bk))), f.resize(n);
        for (long long bi = 0; bi < nc[0]; ++bi)
          x[static_cast<size_t>(bi)] = g.coord(0, corner_index(0, bi));
        ev.values(x, y, z, f);
        std::copy(f.begin(), f.end(), corner_value.begin() + r * nc[0]);
      });
#pragma omp for schedule(static)
    for (long long r = 0; r < nb[1] * nb[2]; ++r)
      trap.run([&] {
        const long long bj = r % nb[1], bk = r / nb[1];
        const size_t n = static_cast<size_t>(nb[0]);
        x.resize(n), y.resize(n), z.resize(n), f.resize(n), gx.resize(n), gy.resize(n),
            gz.resize(n);
        for (long long bi = 0; bi < nb[0]; ++bi) {
          x[static_cast<size_t>(bi)] =
              0.5 * (g.coord(0, corner_index(0, bi)) + g.coord(0, corner_index(0, bi + 1)));
          y[static_cast<size_t>(bi)] =
              0.5 * (g.coord(1, corner_index(1, bj)) + g.coord(1, corner_index(1, bj + 1)));
          z[static_cast<size_t>(bi)] =
              0.5 * (g.coord(2, corner_index(2, bk)) + g.coord(2, corner_index(2, bk + 1)));
        }
        ev.values_gradients(x, y, z, f, gx, gy, gz);
        for (size_t bi = 0; bi < n; ++bi) {
          centre_value[static_cast<size_t>(r * nb[0]) + bi] = f[bi];
          centre_slope[static_cast<size_t>(r * nb[0]) + bi] =
              std::sqrt(gx[bi] * gx[bi] + gy[bi] * gy[bi] + gz[bi] * gz[bi]);
        }
      });
  }
  trap.rethrow();
  st.grid_samples += static_cast<long long>(corner_value.size() + centre_value.size());
  std::vector<long long> kept;
  for (long long b = 0; b < bricks; ++b) {
    const long long bi = b % nb[0], bj = (b / nb[0]) % nb[1], bk = b / (nb[0] * nb[1]);
    double f[9], fmin = std::abs(centre_value[static_cast<size_t>(b)]);
    f[8] = centre_value[static_cast<size_t>(b)];
    for (int c = 0; c < 8; ++c) {
      const auto& d = kCorner[c];
      f[c] =
          corner_value[static_cast<size_t>(((bk + d[2]) * nc[1] + bj + d[1]) * nc[0] + bi + d[0])];
      fmin = std::min(fmin, std::abs(f[c]));
    }
    Vec3 size;
    for (int a = 0; a < 3; ++a) {
      const long long bb = a == 0 ? bi : a == 1 ? bj : bk;
      size[a] = static_cast<double>(corner_index(a, bb + 1) - corner_index(a, bb)) * g.h;
    }
    const double slope = centre_slope[static_cast<size_t>(b)];
    bool mixed = false;
    for (int c = 1; c < 9; ++c) mixed |= is_positive(f[c]) != is_positive(f[0]);
    const bool near = fmin <= o.sparse_margin * slope * 0.5 * size.norm();
    if (mixed || near || !std::isfinite(fmin) || !std::isfinite(slope)) kept.push_back(b);
  }
  st.bricks_kept += static_cast<long long>(kept.size());
  st.seconds_sampling += seconds_since(t0);
  if (stop.stop_requested()) return {};

  // Per brick: sample its nodes, triangulate its cells with edge keys.
  const long long nx = g.nx(), ny = g.ny();
  // Keys sort like the dense path's vertex ids (row, then axis, then x), so both paths number
  // the vertices alike and the clean-up that follows makes the same choices.
  auto key_of = [&](long long i, long long j, long long k, int axis) {
    return static_cast<std::uint64_t>(((k * ny + j) * 3 + axis) * nx + i);
  };
  using KeyTriangle = std::array<std::uint64_t, 3>;
  std::vector<std::vector<KeyTriangle>> tris(kept.size());
  std::vector<std::vector<KeyedCrossing>> cross(kept.size());
  long long active_cells = 0, ambiguous = 0, samples = 0, nan_count = 0;
  double sampling_seconds = 0;
  const CellPolygons* table = cell_polygon_table();
  auto t1 = Clock::now();
  {
    std::vector<std::unique_ptr<RowSampler>> samplers(static_cast<size_t>(workers));
    for (auto& s : samplers) s = std::make_unique<RowSampler>(surface.field, g, poly);
#pragma omp parallel for num_threads(workers) schedule(dynamic, 8) \
    reduction(+ : active_cells, ambiguous, samples, nan_count, sampling_seconds)
    for (long long q = 0; q < static_cast<long long>(kept.size()); ++q)
      trap.run([&] {
        if (stop.stop_requested()) return;
        const long long b = kept[static_cast<size_t>(q)];
        const long long bi = b % nb[0], bj = (b / nb[0]) % nb[1], bk = b / (nb[0] * nb[1]);
        const long long i0 = bi * B, j0 = bj * B, k0 = bk * B;
        const long long mx = corner_index(0, bi + 1) - i0, my = corner_index(1, bj + 1) - j0,
                        mz = corner_index(2, bk + 1) - k0;  // cells in this brick
        const long long sx = mx + 1, sy = my + 1;
        std::vector<double> v((mx + 1) * (my + 1) * (mz + 1));
        RowSampler& sampler = *samplers[static_cast<size_t>(worker_index())];
        const auto ts = Clock::now();
        for (long long kk = 0; kk <= mz; ++kk)
          for (long long jj = 0; jj <= my; ++jj)
            sampler.sample(i0, sx, j0 + jj, k0 + kk, &v[static_cast<size_t>((kk * sy + jj) * sx)]);
        sampling_seconds += seconds_since(ts);
        samples += static_cast<long long>(v.size());
        for (double val : v) nan_count += std::isfinite(val) ? 0 : 1;
        auto& out_t = tris[static_cast<size_t>(q)];
        auto& out_c = cross[static_cast<size_t>(q)];
        for (long long kk = 0; kk < mz; ++kk)
          for (long long jj = 0; jj < my; ++jj)
            for (long long ii = 0; ii < mx; ++ii) {
              double cv[8];
              for (int c = 0; c < 8; ++c) {
                const auto& d = kCorner[c];
                cv[c] = v[static_cast<size_t>(((kk + d[2]) * sy + jj + d[1]) * sx + ii + d[0])];
              }
              int cube_case = 0;
              for (int c = 0; c < 8; ++c) cube_case |= static_cast<int>(is_positive(cv[c])) << c;
              if (cube_case == 0 || cube_case == 255) continue;
              ++active_cells;
              const CellPolygons& polys = cell_entry(
                  table, cube_case, [&](int c) { return cv[c]; }, ambiguous);
              std::uint64_t key[12];
              Vec3 pos[12];
              for (unsigned m = kCrossingEdges[static_cast<size_t>(cube_case)]; m; m &= m - 1) {
                const int e = std::countr_zero(m);
                const int c0 = kEdgeCorners[e][0], c1 = kEdgeCorners[e][1];
                const auto& d = kCorner[c0];
                const int a = kEdgeAxis[e];
                const long long gi = i0 + ii + d[0], gj = j0 + jj + d[1], gk = k0 + kk + d[2];
                key[e] = key_of(gi, gj, gk, a);
                pos[e] = linear_point(g, gi, gj, gk, a, cv[c0], cv[c1]);
                out_c.push_back({key[e], {gi, gj, gk, a, cv[c0], cv[c1]}});
              }
              triangulate_cell(
                  polys, [&](int e) -> const Vec3& { return pos[e]; },
                  [&](int e0, int e1, int e2) {
                    out_t.push_back({key[e0], key[e1], key[e2]});
                  });
            }
        std::sort(out_c.begin(), out_c.end(),
                  [](const KeyedCrossing& l, const KeyedCrossing& r) { return l.key < r.key; });
        out_c.erase(std::unique(out_c.begin(), out_c.end(),
                                [](const KeyedCrossing& l, const KeyedCrossing& r) {
                                  return l.key == r.key;
                                }),
                    out_c.end());
      });
    trap.rethrow();
  }
  if (stop.stop_requested()) return {};
  st.grid_samples += samples;
  st.nan_samples += nan_count;
  // Sampling inside bricks ran on all workers: count its share of the wall time.
  st.seconds_sampling += sampling_seconds / workers;

  // Global vertex numbering: sorted unique keys.
  std::vector<KeyedCrossing> all;
  {
    size_t total = 0;
    for (const auto& c : cross) total += c.size();
    all.reserve(total);
    for (auto& c : cross) {
      all.insert(all.end(), c.begin(), c.end());
      std::vector<KeyedCrossing>().swap(c);
    }
  }
  std::sort(all.begin(), all.end(),
            [](const KeyedCrossing& l, const KeyedCrossing& r) { return l.key < r.key; });
  all.erase(
      std::unique(all.begin(), all.end(),
                  [](const KeyedCrossing& l, const KeyedCrossing& r) { return l.key == r.key; }),
      all.end());
  if (all.size() > kMaxVertices)
    throw Error(
        fmt::format("the mesh would have {} vertices, more than 2^32; lower the "
                    "resolution",
                    all.size()));
  std::vector<std::uint64_t> keys(all.size());
  std::vector<Crossing> crossings(all.size());
  for (size_t n = 0; n < all.size(); ++n) keys[n] = all[n].key, crossings[n] = all[n].c;
  std::vector<KeyedCrossing>().swap(all);

  auto t_ref = Clock::now();
  res.positions.resize(crossings.size());
  {
    std::vector<std::unique_ptr<VertexPlacer>> placers(static_cast<size_t>(workers));
    for (auto& p : placers)
      p = std::make_unique<VertexPlacer>(surface.field, g, poly, o.refine_steps);
    place_vertices_parallel(placers, workers, crossings, res.positions.data(),
                            st.refine_evaluations, st.pole_edges, stop);
  }
  st.seconds_refinement += seconds_since(t_ref);
  if (stop.stop_requested()) return {};

  size_t total = 0;
  std::vector<size_t> start(tris.size() + 1, 0);
  for (size_t q = 0; q < tris.size(); ++q) start[q + 1] = start[q] + tris[q].size();
  total = start.back();
  res.triangles.resize(total);
  auto id_of = [&](std::uint64_t key) {
    return static_cast<std::uint32_t>(std::lower_bound(keys.begin(), keys.end(), key) -
                                      keys.begin());
  };
#pragma omp parallel for num_threads(workers) schedule(dynamic, 16)
  for (long long q = 0; q < static_cast<long long>(tris.size()); ++q)
    trap.run([&] {
      const auto& src = tris[static_cast<size_t>(q)];
      for (size_t t = 0; t < src.size(); ++t)
        res.triangles[start[static_cast<size_t>(q)] + t] = {id_of(src[t][0]), id_of(src[t][1]),
                                                            id_of(src[t][2])};
    });
  trap.rethrow();
  st.active_cells += active_cells;
  st.ambiguous_faces += ambiguous;
  st.edge_vertices += static_cast<long long>(keys.size());
  st.seconds_extraction += seconds_since(t1) - sampling_seconds / workers;
  return res;
}

}  // namespace zeroset::detail
