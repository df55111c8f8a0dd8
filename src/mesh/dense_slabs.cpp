// The polygonizer's dense path: every node sampled; vertex ids from per-row prefix counts
// over bit sets.
//
// The grid is cut into slabs of a few cell layers (slab_layers), handled one at a time by a
// worker from sampling to triangles (see extract_slab), so only a few node layers' values are
// held (not the whole volume) and they are still in cache when used. Vertices are numbered in
// row order (row = (j, k), then axis, then x), the same order whatever the slabs: a slab
// numbers the rows of its own node layers from 0 and carries on into the next slab's first
// layer (the top faces of its last cells), so adding the slab's first global id makes all its
// ids global. That numbering needs the z edges of that layer, so a slab samples two node
// layers beyond its own. Slab sizes depend on the grid only, so the mesh does not depend on
// the thread count.
#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

#if defined(__AVX2__)
#include <immintrin.h>
#endif

#include "polygonize_detail.h"
#include "row_sampling_detail.h"
#include "vertex_placement_detail.h"
#include "zeroset/detail/parallel.h"
#include "zeroset/error.h"

namespace zeroset::detail {
namespace {

// Cell layers per slab: kSlabLayers, fewer on small grids so that they still make eight slabs
// for the workers to share (never fewer than 8 layers: each slab samples two extra layers).
long long slab_layers(const Grid& g) {
  return std::clamp<long long>(g.cells[2] / 8, 8, kSlabLayers);
}

// Per cube corner: which of the cell's four node rows holds it ((dy, dz) = (0,0), (1,0),
// (0,1), (1,1)); per cube edge: the row and x offset of its lower corner.
constexpr std::array<int, 8> kCornerRow = [] {
  std::array<int, 8> row{};
  for (int c = 0; c < 8; ++c) row[c] = kCorner[c][1] + 2 * kCorner[c][2];
  return row;
}();
constexpr std::array<int, 12> kEdgeRow = [] {
  std::array<int, 12> row{};
  for (int e = 0; e < 12; ++e) row[e] = kCornerRow[kEdgeCorners[e][0]];
  return row;
}();
constexpr std::array<int, 12> kEdgeDx = [] {
  std::array<int, 12> dx{};
  for (int e = 0; e < 12; ++e) dx[e] = kCorner[kEdgeCorners[e][0]][0];
  return dx;
}();
// The case of a cell from its corners' sign bits gathered by row: bit q (dx = 0) and bit 4 + q
// (dx = 1) hold the corner in node row q.
constexpr std::array<std::uint8_t, 256> kRowBitsToCase = [] {
  std::array<std::uint8_t, 256> cases{};
  for (int bits = 0; bits < 256; ++bits)
    for (int c = 0; c < 8; ++c)
      if ((bits >> (4 * kCorner[c][0] + kCornerRow[c])) & 1)
        cases[bits] = static_cast<std::uint8_t>(cases[bits] | 1 << c);
  return cases;
}();

// The sign bits of the four node rows of a row of cells, one 64-cell word at a time: `lo` has
// the corners at dx = 0 of cell b at bit b, `hi` those at dx = 1.
struct CellWord {
  std::uint64_t lo[4], hi[4];
#if defined(__AVX2__)
  __m256i lo_v, hi_v;
  void load() {
    lo_v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(lo));
    hi_v = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(hi));
  }
  // Each row's bit b moved to its lane's sign bit and collected by movemask.
  int row_bits(int b) const {
    const __m128i shift = _mm_cvtsi32_si128(63 - b);
    return _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_sll_epi64(lo_v, shift))) |
           _mm256_movemask_pd(_mm256_castsi256_pd(_mm256_sll_epi64(hi_v, shift))) << 4;
  }
#else
  void load() {}
  int row_bits(int b) const {
    int bits = 0;
    for (int q = 0; q < 4; ++q)
      bits |= static_cast<int>((lo[q] >> b) & 1) << q | static_cast<int>((hi[q] >> b) & 1)
                                                            << (4 + q);
    return bits;
  }
#endif
  int cube_case(int b) const { return kRowBitsToCase[static_cast<size_t>(row_bits(b))]; }
};

// An allocator whose resize leaves new elements default-initialised (for numbers: not
// written), for arrays whose every entry used is written first: no pass zeroing them.
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
template <class T>
using ScratchVector = std::vector<T, DefaultInitAllocator<T>>;

// A cell's cycles have at most 12 points in all, so it makes at most 12 − 2 triangles.
constexpr std::ptrdiff_t kMaxCellTriangles = 10;

// What one slab made, with slab-local vertex ids.
struct Slab {
  std::vector<Vec3> positions;  // the vertices of the slab's own node layers
  ScratchVector<Triangle> triangles;
  std::uint64_t numbered = 0;  // vertices numbered, including the next slab's first layer
  long long active_cells = 0, ambiguous = 0, samples = 0, nan_samples = 0, evaluations = 0;
  long long poles = 0;  // sign changes refused as poles or jumps (VertexPlacer::place)
  double seconds_sampling = 0, seconds_refinement = 0;
};

// A worker's arrays, reused from slab to slab (resized, never cleared: every entry used is
// written first).
struct SlabScratch {
  ScratchVector<double> values;
  ScratchVector<std::uint64_t> positive, crossing_bits;
  ScratchVector<std::uint32_t> first_id;
  std::vector<Crossing> crossings;
  ScratchVector<Vec3> linear;
  std::vector<size_t> undefined;  // unrefined vertices on edges with a non-finite end (rare)
};

// Samples, numbers and triangulates the cells of layers [k0, k0 + layers), one node layer at
// a time: numbering a node layer and placing its linear points needs F on the next layer too,
// and the cells of a layer need their two node layers numbered, so once layer L is sampled
// layer L − 1 is numbered and the cells of layer L − 2 are made. F is held for three node
// layers only (slot (L − k0) mod 3), the bit sets, ids and points for the whole slab.
void extract_slab(RowSampler& sampler, VertexPlacer& placer, SlabScratch& scratch, const Grid& g,
                  long long k0, long long layers, Slab& slab) {
  const long long nx = g.nx(), ny = g.ny(), nz = g.nz();
  const long long W = (nx + 63) / 64;
  const long long k_cells = std::min(k0 + layers, nz - 1);   // cell layers [k0, k_cells)
  const long long k_own = k_cells == nz - 1 ? nz : k_cells;  // own node layers [k0, k_own)
  const long long k_num = std::min(k_own + 1, nz);           // numbered node layers
  const long long k_end = std::min(k_own + 2, nz);           // sampled node layers
  const long long rows = ny * (k_end - k0);                  // slab-local rows j + ny·(k − k0)
  const long long num_rows = ny * (k_num - k0);
  const long long own_rows = ny * (k_own - k0);

  ScratchVector<double>& V = scratch.values;
  ScratchVector<std::uint64_t>& P = scratch.positive;
  ScratchVector<std::uint64_t>& C = scratch.crossing_bits;
  ScratchVector<std::uint32_t>& off = scratch.first_id;
  ScratchVector<Vec3>& linear = scratch.linear;
  std::vector<Crossing>& crossings = scratch.crossings;
  V.resize(static_cast<size_t>(3 * ny * nx));
  P.resize(static_cast<size_t>(W * rows));
  C.resize(static_cast<size_t>(num_rows * 3 * W));
  off.resize(C.size());
  linear.clear();
  crossings.clear();
  scratch.undefined.clear();
  auto layer_values = [&](long long k) {  // F on node layer k, row j at j · nx
    return &V[static_cast<size_t>((k - k0) % 3 * ny * nx)];
  };
  const bool refine = placer.refines();
  const std::uint64_t last_node_mask = (nx % 64) ? (1ull << (nx % 64)) - 1 : ~0ull;
  const std::uint64_t last_edge_mask =
      ((nx - 1) % 64) ? (1ull << ((nx - 1) % 64)) - 1 : ~0ull;  // x edges: i ≤ nx − 2
  const long long edge_words = (nx - 1 + 63) / 64;
  std::uint64_t id = 0, own_count = 0;

  // F and its sign bits on node layer k.
  auto sample_layer = [&](long long k) {
    const auto ts = Clock::now();
    double* layer = layer_values(k);
    for (long long j = 0; j < ny; ++j) {
      const long long r = j + ny * (k - k0);
      const long long nans =
          sampler.sample(0, nx, j, k, layer + j * nx, &P[static_cast<size_t>(r * W)]);
      if (r < own_rows) slab.nan_samples += nans;
    }
    slab.samples += nx * ny;
    slab.seconds_sampling += seconds_since(ts);
  };

  // Crossing bits per (row, axis, word) of node layer k, and the id of the first crossing of
  // each: a crossing's id is its word's first id plus the crossings before it in the word.
  // False when the ids run out (the caller reports it).
  auto number_layer = [&](long long k) {
    std::uint64_t next_id = id;
    for (long long j = 0; j < ny; ++j) {
      const long long r = j + ny * (k - k0);
      const std::uint64_t* p = &P[static_cast<size_t>(r * W)];
      std::uint64_t* c = &C[static_cast<size_t>(r * 3 * W)];
      if (r == own_rows) own_count = next_id;
      for (long long w = 0; w < W; ++w) {
        const std::uint64_t next = w + 1 < W ? p[w + 1] : 0;
        std::uint64_t xb = p[w] ^ ((p[w] >> 1) | (next << 63));
        if (w >= edge_words)
          xb = 0;
        else if (w == edge_words - 1)
          xb &= last_edge_mask;
        std::uint64_t yb = j + 1 < ny ? p[w] ^ p[w + W] : 0;
        std::uint64_t zb = k + 1 < nz ? p[w] ^ p[w + W * ny] : 0;
        if (w == W - 1) yb &= last_node_mask, zb &= last_node_mask;
        c[w] = xb, c[W + w] = yb, c[2 * W + w] = zb;
      }
      std::uint32_t* o = &off[static_cast<size_t>(r * 3 * W)];
      for (long long w = 0; w < 3 * W; ++w) {
        o[w] = static_cast<std::uint32_t>(next_id);
        next_id += static_cast<std::uint64_t>(std::popcount(c[w]));
      }
      if (next_id > kMaxVertices) {
        id = next_id;
        return false;
      }
    }
    id = next_id;
    if (k + 1 == k_own && k_own == k_num) own_count = id;  // the slab ends at the grid's top
    return true;
  };

  // The linear points of node layer k's crossings in id order (the cells use those), and the
  // crossings of the own layers to refine.
  const Grid grid = g;  // a copy the stores below cannot alias, so its fields stay in registers
  auto place_layer = [&](long long k) {
    const auto tr = Clock::now();
    const size_t first = linear.size();
    linear.resize(id);
    size_t n = first;
    const bool refine_own = refine && k < k_own;
    const double* layer = layer_values(k);
    const double* next_layer = k + 1 < nz ? layer_values(k + 1) : layer;
    for (long long j = 0; j < ny; ++j) {
      const long long r = j + ny * (k - k0);
      const std::uint64_t* c = &C[static_cast<size_t>(r * 3 * W)];
      const double* row = layer + j * nx;
      const double* ends[3] = {row + 1, j + 1 < ny ? row + nx : row, next_layer + j * nx};
      // Each axis with its number known to the compiler.
      auto along = [&](auto axis) {
        constexpr int a = decltype(axis)::value;
        const double* end = ends[a];
        for (long long w = 0; w < W; ++w)
          for (std::uint64_t b = c[a * W + w]; b; b &= b - 1, ++n) {
            const long long i = w * 64 + std::countr_zero(b);
            const double fa = row[i], fb = end[i];
            linear[n] = linear_point(grid, i, j, k, a, fa, fb);
            if (refine_own)
              crossings.push_back({i, j, k, a, fa, fb});
            else if (!refine && !finite_ends(fa, fb))
              scratch.undefined.push_back(n);
          }
      };
      along(std::integral_constant<int, 0>{});
      along(std::integral_constant<int, 1>{});
      along(std::integral_constant<int, 2>{});
    }
    slab.seconds_refinement += seconds_since(tr);
  };

  // Triangles of the cells of layer k, cell row by cell row. A cell's case comes from the
  // sign bits, its corner values are read only to decide ambiguous faces, and the id of the
  // vertex on its edge e is the first id of the edge's word plus the crossings before it there.
  const CellPolygons* table = cell_polygon_table();
  const std::uint64_t last_cell_mask = last_edge_mask;
  const long long cell_words = edge_words;
  // Where the words of cube edge e's (row, axis) start in C and off, from those of the cell's
  // first node row.
  long long edge_word[12];
  for (int e = 0; e < 12; ++e) {
    const long long row = (kEdgeRow[e] & 1) + (kEdgeRow[e] >> 1) * ny;
    edge_word[e] = (row * 3 + kEdgeAxis[e]) * W;
  }
  // Triangles are written through a pointer, with room for one more cell checked per cell.
  ScratchVector<Triangle>& tris = slab.triangles;
  tris.resize(static_cast<size_t>(2 * nx * ny) + kMaxCellTriangles);  // a guess; grows if needed
  Triangle* tri = tris.data();
  const Triangle* tri_end = tri + tris.size();
  auto triangulate_layer = [&](long long k) {
    const Vec3* lin = linear.data();
    const double* layer = layer_values(k);
    const double* next_layer = layer_values(k + 1);
    Triangle* out = tri;
    long long active = 0;
    for (long long j = 0; j + 1 < ny; ++j) {
      // Node rows of corners (dy, dz) = (0,0), (1,0), (0,1), (1,1).
      const long long r0 = j + ny * (k - k0);
      const long long nr[4] = {r0, r0 + 1, r0 + ny, r0 + ny + 1};
      const double* vr[4] = {layer + j * nx, layer + (j + 1) * nx, next_layer + j * nx,
                             next_layer + (j + 1) * nx};
      const std::uint64_t* pr[4];
      for (int q = 0; q < 4; ++q) pr[q] = &P[static_cast<size_t>(nr[q] * W)];
      for (long long w = 0; w < cell_words; ++w) {
        CellWord cw;
        std::uint64_t all = ~0ull, any = 0;
        for (int q = 0; q < 4; ++q) {
          const std::uint64_t next = w + 1 < W ? pr[q][w + 1] : 0;
          cw.lo[q] = pr[q][w];
          cw.hi[q] = (pr[q][w] >> 1) | (next << 63);
          all &= cw.lo[q] & cw.hi[q];
          any |= cw.lo[q] | cw.hi[q];
        }
        std::uint64_t act = any & ~all;
        if (w == cell_words - 1) act &= last_cell_mask;
        if (!act) continue;
        cw.load();
        const std::uint64_t* crossing_word = &C[static_cast<size_t>(r0 * 3 * W + w)];
        const std::uint32_t* first_id_word = &off[static_cast<size_t>(r0 * 3 * W + w)];
        while (act) {
          const int b = std::countr_zero(act);
          act &= act - 1;
          const long long i = w * 64 + b;
          const int cube_case = cw.cube_case(b);
          ++active;
          // Corner c at (i + dx, j + dy, k + dz), Lorensen numbering.
          const CellPolygons& polys = cell_entry(
              table, cube_case, [&](int c) { return vr[kCornerRow[c]][i + kCorner[c][0]]; },
              slab.ambiguous);
          // The crossings before node i, and before node i + 1 (at b = 63 that is the whole
          // word, and the next word's first id is this one's plus its crossings).
          const std::uint64_t before[2] = {(1ull << b) - 1, (2ull << b) - 1};
          std::uint32_t ids[12];
          for (unsigned m = kCrossingEdges[static_cast<size_t>(cube_case)]; m; m &= m - 1) {
            const int e = std::countr_zero(m);
            const long long at = edge_word[e];
            ids[e] = first_id_word[at] + static_cast<std::uint32_t>(
                                             std::popcount(crossing_word[at] & before[kEdgeDx[e]]));
          }
          if (tri_end - out < kMaxCellTriangles) {
            const size_t used = static_cast<size_t>(out - tris.data());
            tris.resize(2 * tris.size());
            out = tris.data() + used, tri_end = tris.data() + tris.size();
          }
          triangulate_cell(
              polys, [&](int e) -> const Vec3& { return lin[ids[e]]; },
              [&](int e0, int e1, int e2) {
                *out++ = {ids[e0], ids[e1], ids[e2]};
              });
        }
      }
    }
    tri = out;
    slab.active_cells += active;
  };

  long long numbered = k0, triangulated = k0;  // the next layers to number and to triangulate
  for (long long k = k0; k < k_end; ++k) {
    sample_layer(k);
    for (; numbered < k_num && (numbered < k || numbered + 1 == nz); ++numbered) {
      if (!number_layer(numbered)) {
        slab.numbered = id;
        return;
      }
      place_layer(numbered);
    }
    for (; triangulated < k_cells && triangulated + 1 < numbered; ++triangulated)
      triangulate_layer(triangulated);
  }
  slab.numbered = id;
  tris.resize(static_cast<size_t>(tri - tris.data()));

  // The vertices of the own layers: refined in one batch, or the linear points.
  const auto tr = Clock::now();
  slab.positions.resize(own_count);
  if (refine) {
    placer.place(crossings, slab.positions.data(), slab.evaluations, slab.poles);
  } else {
    std::copy(linear.begin(), linear.begin() + static_cast<long>(own_count),
              slab.positions.begin());
    for (size_t n : scratch.undefined)
      if (n < own_count) slab.positions[n] = no_vertex();
  }
  slab.seconds_refinement += seconds_since(tr);
}

}  // namespace

ExtractedMesh extract_dense(const Surface& surface, const Grid& g, const PolygonizeOptions& o,
                            const Polynomial* poly, int workers, PolygonizeStats& st,
                            const std::stop_token& stop) {
  const auto t0 = Clock::now();
  const long long layers = slab_layers(g);
  const long long slabs = (g.cells[2] + layers - 1) / layers;
  // At least four slabs per worker: a worker that the system preempts while it holds a slab
  // then delays the end by a fraction of the work, not by half of it (small grids, where a
  // slab is a quarter of the grid or more, run on one worker).
  workers = static_cast<int>(std::clamp<long long>(slabs / 4, 1, workers));
  std::vector<Slab> out(static_cast<size_t>(slabs));
  ExceptionTrap trap;
  {
    std::vector<std::unique_ptr<RowSampler>> samplers(static_cast<size_t>(workers));
    for (auto& s : samplers) s = std::make_unique<RowSampler>(surface.field, g, poly);
    std::vector<std::unique_ptr<VertexPlacer>> placers(static_cast<size_t>(workers));
    for (auto& p : placers)
      p = std::make_unique<VertexPlacer>(surface.field, g, poly, o.refine_steps);
    std::vector<SlabScratch> scratch(static_cast<size_t>(workers));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
    for (long long s = 0; s < slabs; ++s)
      trap.run([&] {
        if (stop.stop_requested()) return;
        const auto w = static_cast<size_t>(worker_index());
        extract_slab(*samplers[w], *placers[w], scratch[w], g, s * layers, layers,
                     out[static_cast<size_t>(s)]);
      });
    trap.rethrow();
  }
  if (stop.stop_requested()) return {};

  // First global id of each slab; then slab-local ids become global.
  std::vector<std::uint64_t> base(static_cast<size_t>(slabs) + 1, 0);
  for (size_t s = 0; s < out.size(); ++s) {
    if (out[s].numbered > kMaxVertices)
      base[s + 1] = kMaxVertices + 1;
    else
      base[s + 1] = base[s] + out[s].positions.size();
  }
  if (base.back() > kMaxVertices)
    throw Error("the mesh would have more than 2^32 vertices; lower the resolution");
  std::vector<size_t> tri_base(out.size() + 1, 0);
  for (size_t s = 0; s < out.size(); ++s) tri_base[s + 1] = tri_base[s] + out[s].triangles.size();
  ExtractedMesh res;
  res.positions.resize(base.back());
  res.triangles.resize(tri_base.back());
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
  for (long long s = 0; s < slabs; ++s)
    trap.run([&] {
      Slab& slab = out[static_cast<size_t>(s)];
      const auto b = static_cast<std::uint32_t>(base[static_cast<size_t>(s)]);
      std::copy(slab.positions.begin(), slab.positions.end(),
                res.positions.begin() + static_cast<long>(base[static_cast<size_t>(s)]));
      Triangle* dst = res.triangles.data() + tri_base[static_cast<size_t>(s)];  // may be empty
      for (const Triangle& t : slab.triangles) *dst++ = {t[0] + b, t[1] + b, t[2] + b};
      std::vector<Vec3>().swap(slab.positions);
      ScratchVector<Triangle>().swap(slab.triangles);
    });
  trap.rethrow();

  // The slabs ran on all workers: count their sampling and refinement shares of the wall time.
  double sampling = 0, refinement = 0;
  for (const Slab& s : out) {
    st.active_cells += s.active_cells;
    st.ambiguous_faces += s.ambiguous;
    st.grid_samples += s.samples;
    st.nan_samples += s.nan_samples;
    st.pole_edges += s.poles;
    st.refine_evaluations += s.evaluations;
    sampling += s.seconds_sampling;
    refinement += s.seconds_refinement;
  }
  st.edge_vertices += static_cast<long long>(res.positions.size());
  st.seconds_sampling += sampling / workers;
  st.seconds_refinement += refinement / workers;
  st.seconds_extraction += seconds_since(t0) - sampling / workers;
  return res;
}

}  // namespace zeroset::detail
