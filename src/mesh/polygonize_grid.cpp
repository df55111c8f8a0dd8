// The polygonizer's grid: checking the options, fitting the cells to the box, choosing the
// dense or the sparse path, and the plan callers see before they polygonize.
#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/core.h>

#include "polygonize_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/error.h"
#include "zeroset/io/memory.h"

namespace zeroset {
namespace detail {
namespace {

constexpr int kMaxCells = 32768;

void check_options(const PolygonizeOptions& o) {
  if (o.cells < 1 || o.cells > kMaxCells)
    throw InvalidArgument("cells", std::to_string(o.cells),
                          fmt::format("must be between 1 and {}", kMaxCells));
  if (o.brick_cells < 2 || o.brick_cells > 64)
    throw InvalidArgument("brick_cells", std::to_string(o.brick_cells), "must be in [2, 64]");
  if (!(o.sparse_margin > 0) || !std::isfinite(o.sparse_margin))
    throw InvalidArgument("sparse_margin", fmt::format("{}", o.sparse_margin), "must be > 0");
  if (o.refine_steps < 0 || o.refine_steps > 200)
    throw InvalidArgument("refine_steps", std::to_string(o.refine_steps), "must be in [0, 200]");
  if (!(o.clip_snap_fraction >= 0 && o.clip_snap_fraction < 0.5))
    throw InvalidArgument("clip_snap_fraction", fmt::format("{}", o.clip_snap_fraction),
                          "must be in [0, 0.5)");
  if (!(o.collapse_fraction >= 0 && o.collapse_fraction < 0.5))
    throw InvalidArgument("collapse_fraction", fmt::format("{}", o.collapse_fraction),
                          "must be in [0, 0.5)");
  if (o.threads < 0) throw InvalidArgument("threads", std::to_string(o.threads), "must be ≥ 0");
}

double estimate_triangles(const Grid& g) {
  const double cx = static_cast<double>(g.cells[0]), cy = static_cast<double>(g.cells[1]),
               cz = static_cast<double>(g.cells[2]);
  return 4.0 * (cx * cy + cy * cz + cz * cx);
}

}  // namespace

bool clips(const Surface& s, const PolygonizeOptions& o) {
  return o.clip && !s.clip.is_empty_spec();
}

Grid make_grid(const Surface& surface, const PolygonizeOptions& o) {
  check_options(o);
  const Box3 box = o.bounds ? *o.bounds : surface.bounds();
  if (!box.lo.allFinite() || !box.hi.allFinite() || box.is_empty() || box.size().maxCoeff() <= 0)
    throw InvalidArgument("bounds",
                          fmt::format("[{}, {}, {}] .. [{}, {}, {}]", box.lo.x(), box.lo.y(),
                                      box.lo.z(), box.hi.x(), box.hi.y(), box.hi.z()),
                          "the box must be finite and have a positive size");
  Grid g;
  const Vec3 size = box.size();
  g.h = size.maxCoeff() / o.cells;
  // A half space of the clip may lie on the box's face; one more cell on each side then
  // lets the cut, not the end of the grid, make the mesh boundary there.
  const int pad = clips(surface, o) && !surface.clip.planes.empty() ? 1 : 0;
  for (int a = 0; a < 3; ++a) {
    const long long n = std::max(1LL, static_cast<long long>(std::ceil(size[a] / g.h - 1e-9)));
    g.cells[a] = n + 2 * pad;
    g.lo[a] = box.center()[a] - 0.5 * static_cast<double>(g.cells[a]) * g.h;
  }
  // A box that spans [-3, 3] with 128 cells should have its nodes exactly at -3 + i·h.
  if (pad == 0)
    for (int a = 0; a < 3; ++a)
      if (g.cells[a] == static_cast<long long>(std::llround(size[a] / g.h))) g.lo[a] = box.lo[a];
  return g;
}

bool use_sparse(const Grid& g, const PolygonizeOptions& o) {
  if (o.mode != GridMode::kAuto) return o.mode == GridMode::kSparse;
  return static_cast<double>(g.nx()) * static_cast<double>(g.ny()) * static_cast<double>(g.nz()) >
         static_cast<double>(o.sparse_auto_nodes);
}

}  // namespace detail

GridPlan plan_grid(const Surface& surface, const PolygonizeOptions& options) {
  using detail::Grid;
  const Grid g = detail::make_grid(surface, options);
  GridPlan plan;
  plan.cells = g.cells;
  plan.cell_size = g.h;
  plan.box.lo = g.lo;
  plan.box.hi = g.node(g.cells[0], g.cells[1], g.cells[2]);
  plan.sparse = detail::use_sparse(g, options);
  const double nodes =
      static_cast<double>(g.nx()) * static_cast<double>(g.ny()) * static_cast<double>(g.nz());
  // Per estimated triangle: the mesh itself, its construction, and the improver's state.
  const double mesh_bytes = 160.0 * detail::estimate_triangles(g);
  if (plan.sparse) {
    const double B = options.brick_cells;
    plan.estimated_bytes = nodes / (B * B * B) * 40.0 + mesh_bytes;
  } else {
    // Each worker holds F on three node layers (8 bytes a node) and the bit sets and ids of
    // one slab, its node layers plus two (about half a byte a node).
    const double layer_nodes = static_cast<double>(g.nx()) * static_cast<double>(g.ny());
    plan.estimated_bytes = detail::worker_count(options.threads) * layer_nodes *
                               (3 * 8.0 + static_cast<double>(detail::kSlabLayers + 2) * 0.5) +
                           mesh_bytes;
  }
  return plan;
}

void check_grid_memory(const Surface& surface, PolygonizeOptions options,
                       const std::string& option) {
  const MemoryLimit have = available_memory();
  if (!have.known) return;
  const double limit = have.budget();
  const int cells = options.cells;
  auto need = [&](int n) {
    options.cells = n;
    return plan_grid(surface, options).estimated_bytes;
  };
  const double needed = need(cells);
  if (needed <= limit) return;
  int lo = 1, hi = cells;  // need(lo) fits (or nothing does), need(hi) does not
  while (hi - lo > 1) {
    const int mid = lo + (hi - lo) / 2;
    (need(mid) <= limit ? lo : hi) = mid;
  }
  throw InvalidArgument(
      option, std::to_string(cells),
      fmt::format("{}; use {} {} or less", memory_shortfall(needed, have), option, lo));
}

}  // namespace zeroset
