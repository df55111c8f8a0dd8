#include "zeroset/mesh/polygonize.h"

#include <optional>
#include <utility>

#include "mesh_detail.h"
#include "polygonize_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/mesh/mesh_ops.h"

namespace zeroset {

Mesh polygonize(const Surface& surface, const PolygonizeOptions& options, PolygonizeStats* stats,
                std::stop_token stop) {
  using detail::Clock;
  using detail::seconds_since;
  const auto t_start = Clock::now();
  const detail::Grid g = detail::make_grid(surface, options);
  PolygonizeStats st;
  st.grid_bounds.lo = g.lo;
  st.grid_bounds.hi = g.node(g.cells[0], g.cells[1], g.cells[2]);
  for (int a = 0; a < 3; ++a) st.cells[static_cast<size_t>(a)] = static_cast<int>(g.cells[static_cast<size_t>(a)]);
  st.cell_size = g.h;
  st.sparse = detail::use_sparse(g, options);
  surface.field.require_parameters();
  const int workers = detail::worker_count(options.threads);

  std::optional<Polynomial> poly;
  if (options.polynomial_rows && surface.field.is_expandable()) poly = surface.field.polynomial();

  const Polynomial* p = poly ? &*poly : nullptr;
  detail::ExtractedMesh r =
      st.sparse ? detail::extract_sparse(surface, g, options, p, workers, st, stop)
                : detail::extract_dense(surface, g, options, p, workers, st, stop);
  if (stop.stop_requested()) return {};

  const auto t_clean = Clock::now();
  Mesh mesh;
  mesh.positions = std::move(r.positions);
  mesh.triangles = std::move(r.triangles);
  mesh.is_boundary.assign(mesh.positions.size(), 0);
  if (detail::clips(surface, options)) {
    const detail::ClipCutStats cs =
        detail::cut_at_clip(mesh, surface, options.clip_snap_fraction * g.h, workers);
    st.clip_cut_edges = cs.cut_edges;
    st.clip_snapped = cs.snapped;
  }
  if (stop.stop_requested()) return {};
  st.collapsed_edges = static_cast<long long>(collapse_short_edges(mesh, options.collapse_fraction * g.h));
  remove_unreferenced_vertices(mesh);
  detail::flag_open_boundary(mesh);
  if (options.compute_normals) compute_field_normals(mesh, surface, options.threads);
  st.seconds_cleanup = seconds_since(t_clean);
  st.seconds_total = seconds_since(t_start);
  if (stats) *stats = st;
  if (stop.stop_requested()) return {};
  return mesh;
}

}  // namespace zeroset
