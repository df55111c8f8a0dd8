#include "zeroset/mesh/polygonize.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <fmt/core.h>

#if defined(__AVX__)
#include <immintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "cell_triangulation_detail.h"
#include "mc_table_detail.h"
#include "zeroset/detail/bracket.h"
#include "zeroset/detail/parallel.h"
#include "mesh_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/mesh/mesh_ops.h"

namespace zeroset {
namespace {

using Clock = std::chrono::steady_clock;
using detail::CellPolygons;
using detail::IllinoisBracket;
using detail::is_positive;
using detail::kEdgeAxis;
using detail::kEdgeCorners;
using detail::kFaceCanonical;
using detail::madd;
using detail::triangulate_cell;

constexpr int kMaxCells = 32768;
constexpr std::uint64_t kMaxVertices = 0xfffffff0ull;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// A grid of cubic cells; node (i, j, k) is at lo + h·(i, j, k).
struct Grid {
  Vec3 lo = Vec3::Zero();
  double h = 1;
  std::array<long long, 3> cells{0, 0, 0};
  long long nx() const { return cells[0] + 1; }
  long long ny() const { return cells[1] + 1; }
  long long nz() const { return cells[2] + 1; }
  double coord(int axis, long long i) const { return lo[axis] + static_cast<double>(i) * h; }
  Vec3 node(long long i, long long j, long long k) const {
    return {coord(0, i), coord(1, j), coord(2, k)};
  }
};

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

bool clips(const Surface& s, const PolygonizeOptions& o) {
  return o.clip && !s.clip.is_empty_spec();
}

Grid make_grid(const Surface& surface, const PolygonizeOptions& o) {
  check_options(o);
  const Box3 box = o.bounds ? *o.bounds : surface.bounds();
  if (!box.lo.allFinite() || !box.hi.allFinite() || box.is_empty() || box.size().maxCoeff() <= 0)
    throw InvalidArgument("bounds", fmt::format("[{}, {}, {}] .. [{}, {}, {}]", box.lo.x(),
                                                box.lo.y(), box.lo.z(), box.hi.x(), box.hi.y(),
                                                box.hi.z()),
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

double estimate_triangles(const Grid& g) {
  const double cx = static_cast<double>(g.cells[0]), cy = static_cast<double>(g.cells[1]),
               cz = static_cast<double>(g.cells[2]);
  return 4.0 * (cx * cy + cy * cz + cz * cx);
}

bool use_sparse(const Grid& g, const PolygonizeOptions& o) {
  if (o.mode != GridMode::kAuto) return o.mode == GridMode::kSparse;
  return static_cast<double>(g.nx()) * static_cast<double>(g.ny()) * static_cast<double>(g.nz()) >
         static_cast<double>(o.sparse_auto_nodes);
}

// A polynomial F restricted to the grid lines along one axis. Along the line through grid
// coordinates (u, v) of the other two axes (in increasing axis order), F is a univariate
// polynomial in t, the number of cells from the middle node of the whole line: G(t, u, v) =
// F with the axis coordinate coord(mid) + h·t, expanded once. Its coefficient of t^m is a
// polynomial in u whose coefficients depend on v alone; those are kept for the last v (set_v),
// since callers walk lines with v fixed (a layer of rows, the edges of one row), so a line then
// costs one Horner pass in u per coefficient. A node gets the bit-identical value whichever
// caller (a slab, a brick) evaluates it along this axis with the same u and v.
class LineRestriction {
 public:
  LineRestriction(const Polynomial& poly, const Grid& grid, int axis)
      : degree_(poly.degree()), mid_(grid.cells[static_cast<size_t>(axis)] / 2) {
    if (degree_ < 0) return;
    Vec3 origin = Vec3::Zero();
    origin[axis] = grid.coord(axis, mid_);
    const int ua = axis == 0 ? 1 : 0, va = axis == 2 ? 1 : 2;
    const Polynomial translated = poly.translated(origin);
    for (const Monomial& m : translated.terms()) {
      const int e[3] = {m.i, m.j, m.k};
      terms_.push_back({m.c * std::pow(grid.h, e[axis]), e[axis], e[ua], e[va]});
    }
    const size_t n = static_cast<size_t>(degree_ + 1);
    in_u_.resize(n * n);
    v_powers_.resize(n);
  }

  /// −1 for the zero polynomial.
  int degree() const { return degree_; }
  /// t of grid index `index` along the axis.
  double t_of(long long index) const { return static_cast<double>(index - mid_); }

  /// Prepares the lines through this v (kept until another v is set).
  void set_v(double v) {
    if (have_v_ && v == v_) return;
    const size_t n = static_cast<size_t>(degree_ + 1);
    v_powers_[0] = 1;
    for (size_t a = 1; a < n; ++a) v_powers_[a] = v_powers_[a - 1] * v;
    std::fill(in_u_.begin(), in_u_.end(), 0.0);
    for (const Term& m : terms_)
      in_u_[static_cast<size_t>(m.t) * n + static_cast<size_t>(m.u)] +=
          m.c * v_powers_[static_cast<size_t>(m.v)];
    v_ = v, have_v_ = true;
  }

  /// c[m · stride], m = 0..degree: F along the line through (u, v), v the last one set.
  void coefficients_at(double u, double* c, size_t stride) const {
    const size_t n = static_cast<size_t>(degree_ + 1);
    for (size_t m = 0; m < n; ++m) {
      const double* d = &in_u_[m * n];
      double sum = d[n - 1 - m];  // u's degree in the t^m coefficient is at most degree − m
      for (size_t a = n - 1 - m; a-- > 0;) sum = madd(sum, u, d[a]);
      c[m * stride] = sum;
    }
  }

#if defined(__AVX2__) && defined(__FMA__)
  /// The same for four lines through the last v at once, u's lanes: c[m · stride + lane].
  /// Each lane gets the bits of the scalar form.
  void coefficients_at(__m256d u, double* c, size_t stride) const {
    const size_t n = static_cast<size_t>(degree_ + 1);
    for (size_t m = 0; m < n; ++m) {
      const double* d = &in_u_[m * n];
      __m256d sum = _mm256_broadcast_sd(&d[n - 1 - m]);
      for (size_t a = n - 1 - m; a-- > 0;) sum = _mm256_fmadd_pd(sum, u, _mm256_broadcast_sd(&d[a]));
      _mm256_storeu_pd(c + m * stride, sum);
    }
  }
#endif

  /// c[0..degree] of F along the line through (u, v).
  void coefficients(double u, double v, double* c) {
    set_v(v);
    coefficients_at(u, c, 1);
  }

 private:
  struct Term {
    double c;
    int t, u, v;
  };
  int degree_;
  long long mid_;
  std::vector<Term> terms_;
  std::vector<double> in_u_;     // [m · (degree + 1) + a]: coefficient of t^m u^a at v_
  std::vector<double> v_powers_;
  double v_ = 0;
  bool have_v_ = false;
};

// Bit i of bits[i / 64] set where values[i] counts as positive (is_positive); returns how many
// values are NaN. Four (AVX) or two (SSE2) values per compare where available.
long long sign_bits(const double* values, long long n, std::uint64_t* bits) {
  long long nans = 0;
  for (long long b = 0; b < n; b += 64) {
    const long long e = std::min(n, b + 64);
    std::uint64_t word = 0;
    long long i = b;
#if defined(__AVX__)
    __m256d unordered = _mm256_setzero_pd();
    for (; i + 4 <= e; i += 4) {
      const __m256d v = _mm256_loadu_pd(values + i);
      // not (v < 0), true for NaN: NaN counts as positive
      const auto positive =
          static_cast<std::uint64_t>(_mm256_movemask_pd(_mm256_cmp_pd(v, _mm256_setzero_pd(), _CMP_NLT_UQ)));
      word |= positive << (i - b);
      unordered = _mm256_or_pd(unordered, _mm256_cmp_pd(v, v, _CMP_UNORD_Q));
    }
    if (_mm256_movemask_pd(unordered))  // rare: count the NaNs one by one
      for (long long q = b; q < i; ++q) nans += std::isnan(values[q]) ? 1 : 0;
#elif defined(__SSE2__)
    const __m128d zero = _mm_setzero_pd();
    __m128d unordered = _mm_setzero_pd();
    for (; i + 2 <= e; i += 2) {
      const __m128d v = _mm_loadu_pd(values + i);
      // not (v < 0): NaN counts as positive
      const auto positive = static_cast<std::uint64_t>(~_mm_movemask_pd(_mm_cmplt_pd(v, zero)) & 3);
      word |= positive << (i - b);
      unordered = _mm_or_pd(unordered, _mm_cmpunord_pd(v, v));
    }
    if (_mm_movemask_pd(unordered))  // rare: count the NaNs one by one
      for (long long q = b; q < i; ++q) nans += std::isnan(values[q]) ? 1 : 0;
#endif
    for (; i < e; ++i) {
      word |= static_cast<std::uint64_t>(is_positive(values[i])) << (i - b);
      nans += std::isnan(values[i]) ? 1 : 0;
    }
    bits[b / 64] = word;
  }
  return nans;
}

// Samples F at runs of grid nodes along x: through the line restriction for polynomials
// (vectorised Horner), otherwise through the field over structure-of-arrays rows.
class RowSampler {
 public:
  RowSampler(const Field& field, const Grid& grid, const Polynomial* poly) : grid_(grid) {
    if (!poly) {
      eval_.emplace(field);
      return;
    }
    line_.emplace(*poly, grid, 0);
    coeffs_.resize(static_cast<size_t>(std::max(0, line_->degree()) + 1));
    t_.resize(static_cast<size_t>(grid_.nx()));
    for (long long i = 0; i < grid_.nx(); ++i) t_[static_cast<size_t>(i)] = line_->t_of(i);
  }

  /// F at nodes i0 .. i0 + count − 1 of row (j, k) into out. With `bits`, also their sign bits
  /// as sign_bits makes them (bit n for node i0 + n), and returns how many values are NaN.
  long long sample(long long i0, long long count, long long j, long long k, double* out,
                   std::uint64_t* bits = nullptr) {
    if (line_ && line_->degree() >= 0) {
      line_->coefficients(grid_.coord(1, j), grid_.coord(2, k), coeffs_.data());
      // Horner's rule on blocks of nodes held in registers; every node sees the same
      // operations in the same order (fused multiply-adds where the processor has them),
      // whichever block it falls in, so a node's value does not depend on the run.
      const int degree = line_->degree();
      const double* t = &t_[static_cast<size_t>(i0)];
      const double* c = coeffs_.data();
      long long n = 0;
#if defined(__AVX2__) && defined(__FMA__)
      // The sign bits come from the registers too: sixteen nodes are a quarter word.
      long long nans = 0;
      if (bits) std::fill(bits, bits + (count + 63) / 64, 0);
      // Four independent chains of four nodes hide the latency of the multiply-adds.
      for (; n + 16 <= count; n += 16) {
        __m256d acc[4], tt[4];
        for (int q = 0; q < 4; ++q) acc[q] = _mm256_set1_pd(c[degree]), tt[q] = _mm256_loadu_pd(t + n + 4 * q);
        for (int m = degree - 1; m >= 0; --m) {
          const __m256d cm = _mm256_set1_pd(c[m]);
          for (int q = 0; q < 4; ++q) acc[q] = _mm256_fmadd_pd(acc[q], tt[q], cm);
        }
        for (int q = 0; q < 4; ++q) _mm256_storeu_pd(out + n + 4 * q, acc[q]);
        if (!bits) continue;
        std::uint64_t positive = 0;
        __m256d unordered = _mm256_setzero_pd();
        for (int q = 0; q < 4; ++q) {
          // not (v < 0), true for NaN: NaN counts as positive
          positive |= static_cast<std::uint64_t>(_mm256_movemask_pd(
                          _mm256_cmp_pd(acc[q], _mm256_setzero_pd(), _CMP_NLT_UQ)))
                      << (4 * q);
          unordered = _mm256_or_pd(unordered, _mm256_cmp_pd(acc[q], acc[q], _CMP_UNORD_Q));
        }
        bits[n / 64] |= positive << (n % 64);
        if (_mm256_movemask_pd(unordered))  // rare: count the NaNs one by one
          for (long long q = n; q < n + 16; ++q) nans += std::isnan(out[q]) ? 1 : 0;
      }
      for (; n < count; ++n) {
        double v = c[degree];
        for (int m = degree - 1; m >= 0; --m) v = std::fma(v, t[n], c[m]);
        out[n] = v;
        if (!bits) continue;
        bits[n / 64] |= static_cast<std::uint64_t>(is_positive(v)) << (n % 64);
        nans += std::isnan(v) ? 1 : 0;
      }
      return nans;
#else
      for (; n < count; ++n) {
        double v = c[degree];
        for (int m = degree - 1; m >= 0; --m) v = v * t[n] + c[m];
        out[n] = v;
      }
#endif
    } else if (line_) {  // the zero polynomial
      std::fill(out, out + count, 0.0);
    } else {
      x_.resize(static_cast<size_t>(count));
      y_.assign(static_cast<size_t>(count), grid_.coord(1, j));
      z_.assign(static_cast<size_t>(count), grid_.coord(2, k));
      for (long long n = 0; n < count; ++n) x_[static_cast<size_t>(n)] = grid_.coord(0, i0 + n);
      eval_->values(x_, y_, z_, std::span<double>(out, static_cast<size_t>(count)));
    }
    return bits ? sign_bits(out, count, bits) : 0;
  }

 private:
  std::optional<Evaluator> eval_;  // fields that are not polynomials
  const Grid& grid_;
  std::optional<LineRestriction> line_;
  std::vector<double> coeffs_, t_, x_, y_, z_;
};

// One crossing edge: its lower node, axis and the field values at both ends.
struct Crossing {
  long long i, j, k;
  int axis;
  double fa, fb;
};

// Where the sign changes on the edge by linear interpolation, as a fraction of the edge.
double linear_fraction(double fa, double fb) {
  const double s = fa / (fa - fb);
  return std::isfinite(s) ? std::clamp(s, 0.0, 1.0) : 0.5;
}

// Places one vertex on each crossing edge: linear interpolation, then refinement on F
// restricted to the edge. Polynomials: F along the edge is a univariate polynomial (its grid
// line's restriction), so each step is one Horner pass for F and F', and Newton's method
// converges in three or four steps from the linear start; it runs inside the Illinois
// bracket, whose estimate takes over when Newton's steps stop shrinking fast (a double root,
// where Newton would crawl). Other fields: the Illinois method, all edges of a batch
// evaluated together through the field's tape. One per worker.
class VertexPlacer {
 public:
  VertexPlacer(const Field& field, const Grid& grid, const Polynomial* poly, int steps)
      : grid_(grid), steps_(steps) {
    if (steps <= 0) return;  // linear points only: place_batched evaluates nothing
    if (!poly || poly->degree() < 1) {
      eval_.emplace(field);
      return;
    }
    for (int a = 0; a < 3; ++a) lines_[static_cast<size_t>(a)].emplace(*poly, grid, a);
    nc_ = static_cast<size_t>(poly->degree() + 1);
    coeffs_.resize(nc_ * kStride);
  }

  /// False when vertices stay at the linear interpolation (no refinement steps).
  bool refines() const { return steps_ > 0; }

  void place(std::span<const Crossing> in, Vec3* out, long long& evaluations) {
    if (lines_[0]) place_polynomial(in, out, evaluations);
    else place_batched(in, out, evaluations);
  }

 private:
  Vec3 point(const Crossing& c, double s) const {
    Vec3 p = grid_.node(c.i, c.j, c.k);
    p[c.axis] += std::clamp(s, 0.0, 1.0) * grid_.h;
    return p;
  }

  // Edges are refined in lockstep blocks of kLanes: each step is a chain of dependent
  // multiply-adds and divisions, so independent edges side by side keep the processor busy
  // (and the Horner loop is one vector operation per four lanes). Finished lanes stay put.
  // The coefficients of kChunk edges at a time are held lane by lane: coeffs_[m · kStride +
  // edge], kLanes columns to spare for a last block or four-line pass that runs over.
  static constexpr int kLanes = 8;
  static constexpr size_t kChunk = 256, kStride = kChunk + kLanes;

  // An edge's line comes from the restriction along its axis with v fixed (set_v builds a
  // table from all terms of F, the costly part) and a Horner pass in u:
  //   x edges: (u, v) = (y, z) and y edges: (u, v) = (x, z), v fixed for a whole node layer;
  //   z edges: (u, v) = (x, y), v fixed for a whole xz plane: they are taken by j rather
  //   than in row order, so that each plane's table is built once.
  void place_polynomial(std::span<const Crossing> in, Vec3* out, long long& evaluations) {
    order_.clear();
    long long j_lo = std::numeric_limits<long long>::max();
    long long j_hi = std::numeric_limits<long long>::min();
    size_t z_count = 0;
    for (size_t n = 0; n < in.size(); ++n)
      if (in[n].axis < 2) order_.push_back(static_cast<std::uint32_t>(n));
      else ++z_count, j_lo = std::min(j_lo, in[n].j), j_hi = std::max(j_hi, in[n].j);
    if (z_count > 0) {  // the z edges after them, by j (a stable counting sort)
      bucket_.assign(static_cast<size_t>(j_hi - j_lo + 2), 0);
      for (size_t n = 0; n < in.size(); ++n)
        if (in[n].axis == 2) ++bucket_[static_cast<size_t>(in[n].j - j_lo + 1)];
      for (size_t b = 1; b < bucket_.size(); ++b) bucket_[b] += bucket_[b - 1];
      const size_t first = order_.size();
      order_.resize(first + z_count);
      for (size_t n = 0; n < in.size(); ++n)
        if (in[n].axis == 2)
          order_[first + bucket_[static_cast<size_t>(in[n].j - j_lo)]++] = static_cast<std::uint32_t>(n);
    }
    // The fractions come back in that order; the points go out in the crossings' order.
    fraction_.resize(in.size());
    for (size_t c0 = 0; c0 < order_.size(); c0 += kChunk) {
      const size_t len = std::min(kChunk, order_.size() - c0);
      const std::uint32_t* edge = &order_[c0];
      fill_chunk(in, edge, len);
      for (size_t b = 0; b < len; b += kLanes)
        evaluations += refine_block(b, static_cast<int>(std::min<size_t>(kLanes, len - b)));
      for (size_t e = 0; e < len; ++e) fraction_[edge[e]] = s_[e];
    }
    for (size_t n = 0; n < in.size(); ++n) out[n] = point(in[n], fraction_[n]);
  }

  // Coefficients, t at the lower node, end values and the linear start of edges[0..len).
  void fill_chunk(std::span<const Crossing> in, const std::uint32_t* edge, size_t len) {
    double* C = coeffs_.data();
    for (size_t e = 0; e < len;) {
      // A run of edges along one axis whose lines share v.
      const int axis = in[edge[e]].axis;
      auto v_index = [&](size_t f) { return axis == 2 ? in[edge[f]].j : in[edge[f]].k; };
      const long long v = v_index(e);
      size_t end = e + 1;
      while (end < len && in[edge[end]].axis == axis && v_index(end) == v) ++end;
      LineRestriction& line = *lines_[static_cast<size_t>(axis)];
      line.set_v(grid_.coord(axis == 2 ? 1 : 2, v));
      auto u_of = [&](size_t f) {
        const Crossing& x = in[edge[f]];
        return axis == 0 ? grid_.coord(1, x.j) : grid_.coord(0, x.i);
      };
#if defined(__AVX2__) && defined(__FMA__)
      // Four lines at a time; a last group short of four repeats its last edge into columns
      // that the next run overwrites (or past the chunk's end).
      for (size_t f = e; f < end; f += 4) {
        const __m256d u = _mm256_setr_pd(u_of(f), u_of(std::min(f + 1, end - 1)),
                                         u_of(std::min(f + 2, end - 1)), u_of(std::min(f + 3, end - 1)));
        line.coefficients_at(u, C + f, kStride);
      }
#else
      for (size_t f = e; f < end; ++f) line.coefficients_at(u_of(f), C + f, kStride);
#endif
      for (; e < end; ++e) {
        const Crossing& x = in[edge[e]];
        t0_[e] = line.t_of(axis == 0 ? x.i : axis == 1 ? x.j : x.k);
        fa_[e] = x.fa, fb_[e] = x.fb;
        s_[e] = linear_fraction(x.fa, x.fb);
      }
    }
    // The last block's idle lanes: harmless finite values.
    for (size_t e = len; e % kLanes != 0; ++e) {
      for (size_t m = 0; m < nc_; ++m) C[m * kStride + e] = 0;
      t0_[e] = 0, fa_[e] = -1, fb_[e] = 1, s_[e] = 0.5;
    }
  }

#if defined(__AVX2__) && defined(__FMA__)
  // Refines lanes b..b + 7 in lockstep (see IllinoisBracket for the scalar form of the bracket
  // and its estimate): leaves s_ refined; returns the evaluations of F. Two vectors of four
  // lanes go side by side, as each step is a chain of dependent operations.
  long long refine_block(size_t b, int lanes) {
    constexpr int kGroups = kLanes / 4;
    const int degree = lines_[0]->degree();
    const double* C = coeffs_.data() + b;
    long long evaluations = 0;
    const __m256d zero = _mm256_setzero_pd(), half = _mm256_set1_pd(0.5);
    const __m256d one = _mm256_set1_pd(1.0), minus_one = _mm256_set1_pd(-1.0);
    const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
    auto finite = [&](__m256d x) { return _mm256_cmp_pd(_mm256_sub_pd(x, x), zero, _CMP_EQ_OQ); };
    auto within = [&](__m256d x, __m256d a, __m256d c) {  // false for NaN
      return _mm256_and_pd(_mm256_cmp_pd(x, a, _CMP_GE_OQ), _mm256_cmp_pd(x, c, _CMP_LE_OQ));
    };
    __m256d lo[kGroups], hi[kGroups], flo[kGroups], fhi[kGroups], last[kGroups], sv[kGroups],
        last_move[kGroups], act[kGroups], tg[kGroups];
    for (int g = 0; g < kGroups; ++g) {
      const size_t at = b + 4 * static_cast<size_t>(g);
      lo[g] = zero, hi[g] = one, last[g] = zero, sv[g] = _mm256_loadu_pd(&s_[at]);
      flo[g] = _mm256_loadu_pd(&fa_[at]), fhi[g] = _mm256_loadu_pd(&fb_[at]);
      last_move[g] = _mm256_set1_pd(std::numeric_limits<double>::infinity());
      tg[g] = _mm256_loadu_pd(&t0_[at]);
      // Active: a lane in use whose end values are finite.
      const __m256d in_use =
          _mm256_cmp_pd(_mm256_setr_pd(0, 1, 2, 3), _mm256_set1_pd(lanes - 4 * g), _CMP_LT_OQ);
      act[g] = steps_ > 0 ? _mm256_and_pd(in_use, _mm256_and_pd(finite(flo[g]), finite(fhi[g]))) : zero;
    }
    for (int it = 0; it < steps_; ++it) {
      int mask = 0;
      for (int g = 0; g < kGroups; ++g) mask |= _mm256_movemask_pd(act[g]) << (4 * g);
      if (!mask) break;
      evaluations += std::popcount(static_cast<unsigned>(mask));
      // F and its derivative by Horner's rule.
      __m256d t[kGroups], f[kGroups], df[kGroups];
      for (int g = 0; g < kGroups; ++g) {
        t[g] = _mm256_add_pd(tg[g], sv[g]);
        f[g] = _mm256_loadu_pd(C + static_cast<size_t>(degree) * kStride + 4 * static_cast<size_t>(g));
        df[g] = zero;
      }
      for (int m = degree - 1; m >= 0; --m)
        for (int g = 0; g < kGroups; ++g) {
          const __m256d cm =
              _mm256_loadu_pd(C + static_cast<size_t>(m) * kStride + 4 * static_cast<size_t>(g));
          df[g] = _mm256_fmadd_pd(df[g], t[g], f[g]);
          f[g] = _mm256_fmadd_pd(f[g], t[g], cm);
        }
      for (int g = 0; g < kGroups; ++g) {
        // An exact root or a non-finite value ends the lane where it is.
        const __m256d stop = _mm256_or_pd(_mm256_cmp_pd(f[g], zero, _CMP_EQ_OQ),
                                          _mm256_andnot_pd(finite(f[g]), act[g]));
        const __m256d step = _mm256_andnot_pd(stop, act[g]);
        // The bracket: s replaces the end whose value has f's sign (is_positive alike); the
        // value of an end kept twice in a row is halved.
        const __m256d same = _mm256_xor_pd(_mm256_xor_pd(_mm256_cmp_pd(f[g], zero, _CMP_NLT_UQ),
                                                         _mm256_cmp_pd(fhi[g], zero, _CMP_NLT_UQ)),
                                           _mm256_castsi256_pd(_mm256_set1_epi64x(-1)));
        const __m256d up = _mm256_and_pd(step, same), down = _mm256_andnot_pd(same, step);
        const __m256d halve_lo = _mm256_and_pd(up, _mm256_cmp_pd(last[g], one, _CMP_EQ_OQ));
        const __m256d halve_hi = _mm256_and_pd(down, _mm256_cmp_pd(last[g], minus_one, _CMP_EQ_OQ));
        flo[g] = _mm256_blendv_pd(flo[g], _mm256_mul_pd(flo[g], half), halve_lo);
        fhi[g] = _mm256_blendv_pd(fhi[g], _mm256_mul_pd(fhi[g], half), halve_hi);
        hi[g] = _mm256_blendv_pd(hi[g], sv[g], up), fhi[g] = _mm256_blendv_pd(fhi[g], f[g], up);
        lo[g] = _mm256_blendv_pd(lo[g], sv[g], down), flo[g] = _mm256_blendv_pd(flo[g], f[g], down);
        last[g] = _mm256_blendv_pd(_mm256_blendv_pd(last[g], minus_one, down), one, up);
        const __m256d left = _mm256_min_pd(lo[g], hi[g]), right = _mm256_max_pd(lo[g], hi[g]);
        // Newton's step while it converges fast (a quarter of the last move or less, as near
        // a simple root); else the Illinois estimate, which does not crawl where the surface
        // touches the edge (a double root); else bisection.
        const __m256d newton = _mm256_sub_pd(sv[g], _mm256_div_pd(f[g], df[g]));
        const __m256d illinois =
            _mm256_sub_pd(hi[g], _mm256_div_pd(_mm256_mul_pd(fhi[g], _mm256_sub_pd(hi[g], lo[g])),
                                               _mm256_sub_pd(fhi[g], flo[g])));
        const __m256d fast = _mm256_and_pd(
            within(newton, left, right),
            _mm256_cmp_pd(_mm256_and_pd(_mm256_sub_pd(newton, sv[g]), abs_mask),
                          _mm256_mul_pd(_mm256_set1_pd(0.25), last_move[g]), _CMP_LE_OQ));
        __m256d n = _mm256_blendv_pd(_mm256_mul_pd(half, _mm256_add_pd(lo[g], hi[g])), illinois,
                                     within(illinois, left, right));
        n = _mm256_blendv_pd(n, newton, fast);
        // Converged when s no longer moves; n stays in the bracket, of which s is an end, so
        // a bracket narrower than that ends the search too.
        const __m256d move = _mm256_and_pd(_mm256_sub_pd(n, sv[g]), abs_mask);
        const __m256d done = _mm256_cmp_pd(move, _mm256_set1_pd(1e-13), _CMP_LE_OQ);
        last_move[g] = move;
        sv[g] = _mm256_blendv_pd(sv[g], n, step);
        act[g] = _mm256_andnot_pd(_mm256_or_pd(stop, _mm256_and_pd(done, step)), act[g]);
      }
    }
    for (int g = 0; g < kGroups; ++g) _mm256_storeu_pd(&s_[b + 4 * static_cast<size_t>(g)], sv[g]);
    return evaluations;
  }
#else
  long long refine_block(size_t b, int lanes) {
    const int degree = lines_[0]->degree();
    const double* C = coeffs_.data() + b;
    long long evaluations = 0;
    for (int q = 0; q < lanes; ++q) {
      const size_t e = b + static_cast<size_t>(q);
      if (!std::isfinite(fa_[e]) || !std::isfinite(fb_[e])) continue;
      IllinoisBracket bracket(fa_[e], fb_[e]);
      double s = s_[e], last_move = std::numeric_limits<double>::infinity();
      for (int it = 0; it < steps_; ++it) {
        const double t = t0_[e] + s;
        double f = C[static_cast<size_t>(degree) * kStride + static_cast<size_t>(q)], df = 0;
        for (int m = degree - 1; m >= 0; --m) {
          df = madd(df, t, f);
          f = madd(f, t, C[static_cast<size_t>(m) * kStride + static_cast<size_t>(q)]);
        }
        ++evaluations;
        if (f == 0 || !std::isfinite(f)) break;
        bracket.update(s, f);
        const double newton = s - f / df;
        const bool fast = newton >= std::min(bracket.lo, bracket.hi) &&
                          newton <= std::max(bracket.lo, bracket.hi) &&
                          std::abs(newton - s) <= 0.25 * last_move;
        const double n = fast ? newton : bracket.estimate();
        last_move = std::abs(n - s);
        s = n;
        if (last_move <= 1e-13) break;
      }
      s_[e] = s;
    }
    return evaluations;
  }
#endif

  void place_batched(std::span<const Crossing> in, Vec3* out, long long& evaluations) {
    const size_t n = in.size();
    brackets_.clear();
    t_.resize(n);
    active_.resize(n);
    for (size_t e = 0; e < n; ++e) {
      brackets_.emplace_back(in[e].fa, in[e].fb);
      t_[e] = linear_fraction(in[e].fa, in[e].fb);
      active_[e] = e;
    }
    for (int it = 0; it < steps_ && !active_.empty(); ++it) {
      const size_t m = active_.size();
      x_.resize(m), y_.resize(m), z_.resize(m), f_.resize(m);
      for (size_t q = 0; q < m; ++q) {
        const Vec3 p = point(in[active_[q]], t_[active_[q]]);
        x_[q] = p.x(), y_[q] = p.y(), z_[q] = p.z();
      }
      eval_->values(x_, y_, z_, f_);
      evaluations += static_cast<long long>(m);
      size_t kept = 0;
      for (size_t q = 0; q < m; ++q) {
        const size_t e = active_[q];
        if (f_[q] == 0) continue;  // exact root
        bool done = false;
        t_[e] = brackets_[e].next(t_[e], f_[q], done);
        if (!done) active_[kept++] = e;
      }
      active_.resize(kept);
    }
    for (size_t e = 0; e < n; ++e) out[e] = point(in[e], t_[e]);
  }

  std::optional<Evaluator> eval_;  // fields that are not polynomials
  const Grid& grid_;
  int steps_;
  std::array<std::optional<LineRestriction>, 3> lines_;
  // Polynomials: the edges in the order they are taken, counting-sort buckets, and per edge of
  // a chunk its line's coefficients (nc_ of them), t of its lower node, end values and
  // fraction s.
  std::vector<std::uint32_t> order_;
  std::vector<size_t> bucket_;
  std::vector<double> fraction_;
  size_t nc_ = 0;
  std::vector<double> coeffs_;
  double t0_[kChunk + kLanes], fa_[kChunk + kLanes], fb_[kChunk + kLanes], s_[kChunk + kLanes];
  // Other fields.
  std::vector<IllinoisBracket> brackets_;
  std::vector<double> t_, x_, y_, z_, f_;
  std::vector<size_t> active_;
};

// Places a batch of crossings split over the workers (chunks of a few thousand edges).
void place_vertices_parallel(std::vector<std::unique_ptr<VertexPlacer>>& placers, int workers,
                             const std::vector<Crossing>& in, Vec3* out, long long& evaluations,
                             const std::stop_token& stop) {
  constexpr size_t kChunk = 4096;
  const long long chunks = static_cast<long long>((in.size() + kChunk - 1) / kChunk);
  long long evals = 0;
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1) reduction(+ : evals)
  for (long long c = 0; c < chunks; ++c) {
    if (stop.stop_requested()) continue;
    const size_t b = static_cast<size_t>(c) * kChunk, e = std::min(in.size(), b + kChunk);
    placers[static_cast<size_t>(detail::worker_index())]->place(
        std::span<const Crossing>(in.data() + b, e - b), out + b, evals);
  }
  evaluations += evals;
}

// The linear interpolation of the crossing on the edge from node (i, j, k) along `axis`. The
// triangulation of each cube uses these points (not the refined ones) so that the dense and
// the sparse path, which refines later, triangulate alike.
Vec3 linear_point(const Grid& g, long long i, long long j, long long k, int axis, double fa,
                  double fb) {
  Vec3 p = g.node(i, j, k);
  p[axis] += linear_fraction(fa, fb) * g.h;
  return p;
}


// The table entry of a cell of the given case: its ambiguous faces are decided by the
// asymptotic decider on `corner(c)`, the value at corner c (Lorensen numbering), read only
// for those faces. Counts the decisions in `ambiguous`.
template <class Corner>
const CellPolygons& cell_entry(const CellPolygons* table, int cube_case, Corner&& corner,
                               long long& ambiguous) {
  const int amb = detail::kAmbiguousFaces[static_cast<size_t>(cube_case)];
  int rank = 0;
  if (amb) {  // rare
    int t = 0;
    for (int f = 0; f < 6; ++f) {
      if (!((amb >> f) & 1)) continue;
      const auto& q = kFaceCanonical[f];
      if (detail::positive_corners_connected(corner(q[0]), corner(q[1]), corner(q[2]), corner(q[3])))
        rank |= 1 << t;
      ++t;
    }
    ambiguous += std::popcount(static_cast<unsigned>(amb));
  }
  return table[detail::kCaseFirst[static_cast<size_t>(cube_case)] + static_cast<size_t>(rank)];
}


using Triangle = std::array<std::uint32_t, 3>;

// ---------------------------------------------------------------------------------------
// Dense path: every node sampled; vertex ids from per-row prefix counts over bit sets.
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

struct DenseResult {
  std::vector<Vec3> positions;
  std::vector<Triangle> triangles;
};

constexpr long long kSlabLayers = 16;

// Cell layers per slab: kSlabLayers, fewer on small grids so that they still make eight slabs
// for the workers to share (never fewer than 8 layers: each slab samples two extra layers).
long long slab_layers(const Grid& g) { return std::clamp<long long>(g.cells[2] / 8, 8, kSlabLayers); }

// Per cube corner: which of the cell's four node rows holds it ((dy, dz) = (0,0), (1,0),
// (0,1), (1,1)); per cube edge: the row and x offset of its lower corner.
constexpr std::array<int, 8> kCornerRow = [] {
  std::array<int, 8> row{};
  for (int c = 0; c < 8; ++c) row[c] = detail::kCorner[c][1] + 2 * detail::kCorner[c][2];
  return row;
}();
constexpr std::array<int, 12> kEdgeRow = [] {
  std::array<int, 12> row{};
  for (int e = 0; e < 12; ++e) row[e] = kCornerRow[kEdgeCorners[e][0]];
  return row;
}();
constexpr std::array<int, 12> kEdgeDx = [] {
  std::array<int, 12> dx{};
  for (int e = 0; e < 12; ++e) dx[e] = detail::kCorner[kEdgeCorners[e][0]][0];
  return dx;
}();
// The case of a cell from its corners' sign bits gathered by row: bit q (dx = 0) and bit 4 + q
// (dx = 1) hold the corner in node row q.
constexpr std::array<std::uint8_t, 256> kRowBitsToCase = [] {
  std::array<std::uint8_t, 256> cases{};
  for (int bits = 0; bits < 256; ++bits)
    for (int c = 0; c < 8; ++c)
      if ((bits >> (4 * detail::kCorner[c][0] + kCornerRow[c])) & 1)
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
      bits |= static_cast<int>((lo[q] >> b) & 1) << q | static_cast<int>((hi[q] >> b) & 1) << (4 + q);
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
  std::uint64_t numbered = 0;   // vertices numbered, including the next slab's first layer
  long long active_cells = 0, ambiguous = 0, samples = 0, nan_samples = 0, evaluations = 0;
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
  const long long k_cells = std::min(k0 + layers, nz - 1);  // cell layers [k0, k_cells)
  const long long k_own = k_cells == nz - 1 ? nz : k_cells;      // own node layers [k0, k_own)
  const long long k_num = std::min(k_own + 1, nz);               // numbered node layers
  const long long k_end = std::min(k_own + 2, nz);               // sampled node layers
  const long long rows = ny * (k_end - k0);                      // slab-local rows j + ny·(k − k0)
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
      const long long nans = sampler.sample(0, nx, j, k, layer + j * nx, &P[static_cast<size_t>(r * W)]);
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
        if (w >= edge_words) xb = 0;
        else if (w == edge_words - 1) xb &= last_edge_mask;
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
            if (refine_own) crossings.push_back({i, j, k, a, fa, fb});
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
  const CellPolygons* table = detail::cell_polygon_table();
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
              table, cube_case, [&](int c) { return vr[kCornerRow[c]][i + detail::kCorner[c][0]]; },
              slab.ambiguous);
          // The crossings before node i, and before node i + 1 (at b = 63 that is the whole
          // word, and the next word's first id is this one's plus its crossings).
          const std::uint64_t before[2] = {(1ull << b) - 1, (2ull << b) - 1};
          std::uint32_t ids[12];
          for (unsigned m = detail::kCrossingEdges[static_cast<size_t>(cube_case)]; m; m &= m - 1) {
            const int e = std::countr_zero(m);
            const long long at = edge_word[e];
            ids[e] = first_id_word[at] +
                     static_cast<std::uint32_t>(std::popcount(crossing_word[at] & before[kEdgeDx[e]]));
          }
          if (tri_end - out < kMaxCellTriangles) {
            const size_t used = static_cast<size_t>(out - tris.data());
            tris.resize(2 * tris.size());
            out = tris.data() + used, tri_end = tris.data() + tris.size();
          }
          triangulate_cell(
              polys, [&](int e) -> const Vec3& { return lin[ids[e]]; },
              [&](int e0, int e1, int e2) { *out++ = {ids[e0], ids[e1], ids[e2]}; });
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
  if (refine) placer.place(crossings, slab.positions.data(), slab.evaluations);
  else std::copy(linear.begin(), linear.begin() + static_cast<long>(own_count), slab.positions.begin());
  slab.seconds_refinement += seconds_since(tr);
}

DenseResult extract_dense(const Surface& surface, const Grid& g, const PolygonizeOptions& o,
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
  {
    std::vector<std::unique_ptr<RowSampler>> samplers(static_cast<size_t>(workers));
    for (auto& s : samplers) s = std::make_unique<RowSampler>(surface.field, g, poly);
    std::vector<std::unique_ptr<VertexPlacer>> placers(static_cast<size_t>(workers));
    for (auto& p : placers) p = std::make_unique<VertexPlacer>(surface.field, g, poly, o.refine_steps);
    std::vector<SlabScratch> scratch(static_cast<size_t>(workers));
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
    for (long long s = 0; s < slabs; ++s) {
      if (stop.stop_requested()) continue;
      const auto w = static_cast<size_t>(detail::worker_index());
      extract_slab(*samplers[w], *placers[w], scratch[w], g, s * layers, layers,
                   out[static_cast<size_t>(s)]);
    }
  }
  if (stop.stop_requested()) return {};

  // First global id of each slab; then slab-local ids become global.
  std::vector<std::uint64_t> base(static_cast<size_t>(slabs) + 1, 0);
  for (size_t s = 0; s < out.size(); ++s) {
    if (out[s].numbered > kMaxVertices) base[s + 1] = kMaxVertices + 1;
    else base[s + 1] = base[s] + out[s].positions.size();
  }
  if (base.back() > kMaxVertices)
    throw Error("the mesh would have more than 2^32 vertices; lower the resolution");
  std::vector<size_t> tri_base(out.size() + 1, 0);
  for (size_t s = 0; s < out.size(); ++s) tri_base[s + 1] = tri_base[s] + out[s].triangles.size();
  DenseResult res;
  res.positions.resize(base.back());
  res.triangles.resize(tri_base.back());
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1)
  for (long long s = 0; s < slabs; ++s) {
    Slab& slab = out[static_cast<size_t>(s)];
    const auto b = static_cast<std::uint32_t>(base[static_cast<size_t>(s)]);
    std::copy(slab.positions.begin(), slab.positions.end(),
              res.positions.begin() + static_cast<long>(base[static_cast<size_t>(s)]));
    Triangle* dst = &res.triangles[tri_base[static_cast<size_t>(s)]];
    for (const Triangle& t : slab.triangles) *dst++ = {t[0] + b, t[1] + b, t[2] + b};
    std::vector<Vec3>().swap(slab.positions);
    ScratchVector<Triangle>().swap(slab.triangles);
  }

  // The slabs ran on all workers: count their sampling and refinement shares of the wall time.
  double sampling = 0, refinement = 0;
  for (const Slab& s : out) {
    st.active_cells += s.active_cells;
    st.ambiguous_faces += s.ambiguous;
    st.grid_samples += s.samples;
    st.nan_samples += s.nan_samples;
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

// ---------------------------------------------------------------------------------------
// Sparse path: bricks near the surface; vertices identified by a global edge key.

struct KeyedCrossing {
  std::uint64_t key;
  Crossing c;
};

DenseResult extract_sparse(const Surface& surface, const Grid& g, const PolygonizeOptions& o,
                           const Polynomial* poly, int workers, PolygonizeStats& st,
                           const std::stop_token& stop) {
  DenseResult res;
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
  detail::EvaluatorPool pool(surface.field, workers);
#pragma omp parallel num_threads(workers)
  {
    std::vector<double> x, y, z, f, gx, gy, gz;
    Evaluator& ev = pool.local();
#pragma omp for schedule(static)
    for (long long r = 0; r < nc[1] * nc[2]; ++r) {
      const long long bj = r % nc[1], bk = r / nc[1];
      const size_t n = static_cast<size_t>(nc[0]);
      x.resize(n), y.assign(n, g.coord(1, corner_index(1, bj))),
          z.assign(n, g.coord(2, corner_index(2, bk))), f.resize(n);
      for (long long bi = 0; bi < nc[0]; ++bi) x[static_cast<size_t>(bi)] = g.coord(0, corner_index(0, bi));
      ev.values(x, y, z, f);
      std::copy(f.begin(), f.end(), corner_value.begin() + r * nc[0]);
    }
#pragma omp for schedule(static)
    for (long long r = 0; r < nb[1] * nb[2]; ++r) {
      const long long bj = r % nb[1], bk = r / nb[1];
      const size_t n = static_cast<size_t>(nb[0]);
      x.resize(n), y.resize(n), z.resize(n), f.resize(n), gx.resize(n), gy.resize(n), gz.resize(n);
      for (long long bi = 0; bi < nb[0]; ++bi) {
        x[static_cast<size_t>(bi)] = 0.5 * (g.coord(0, corner_index(0, bi)) + g.coord(0, corner_index(0, bi + 1)));
        y[static_cast<size_t>(bi)] = 0.5 * (g.coord(1, corner_index(1, bj)) + g.coord(1, corner_index(1, bj + 1)));
        z[static_cast<size_t>(bi)] = 0.5 * (g.coord(2, corner_index(2, bk)) + g.coord(2, corner_index(2, bk + 1)));
      }
      ev.values_gradients(x, y, z, f, gx, gy, gz);
      for (size_t bi = 0; bi < n; ++bi) {
        centre_value[static_cast<size_t>(r * nb[0]) + bi] = f[bi];
        centre_slope[static_cast<size_t>(r * nb[0]) + bi] =
            std::sqrt(gx[bi] * gx[bi] + gy[bi] * gy[bi] + gz[bi] * gz[bi]);
      }
    }
  }
  st.grid_samples += static_cast<long long>(corner_value.size() + centre_value.size());
  std::vector<long long> kept;
  for (long long b = 0; b < bricks; ++b) {
    const long long bi = b % nb[0], bj = (b / nb[0]) % nb[1], bk = b / (nb[0] * nb[1]);
    double f[9], fmin = std::abs(centre_value[static_cast<size_t>(b)]);
    f[8] = centre_value[static_cast<size_t>(b)];
    for (int c = 0; c < 8; ++c) {
      const auto& d = detail::kCorner[c];
      f[c] = corner_value[static_cast<size_t>(((bk + d[2]) * nc[1] + bj + d[1]) * nc[0] + bi + d[0])];
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
  const CellPolygons* table = detail::cell_polygon_table();
  auto t1 = Clock::now();
  {
    std::vector<std::unique_ptr<RowSampler>> samplers(static_cast<size_t>(workers));
    for (auto& s : samplers) s = std::make_unique<RowSampler>(surface.field, g, poly);
#pragma omp parallel for num_threads(workers) schedule(dynamic, 8) \
    reduction(+ : active_cells, ambiguous, samples, nan_count, sampling_seconds)
    for (long long q = 0; q < static_cast<long long>(kept.size()); ++q) {
      if (stop.stop_requested()) continue;
      const long long b = kept[static_cast<size_t>(q)];
      const long long bi = b % nb[0], bj = (b / nb[0]) % nb[1], bk = b / (nb[0] * nb[1]);
      const long long i0 = bi * B, j0 = bj * B, k0 = bk * B;
      const long long mx = corner_index(0, bi + 1) - i0, my = corner_index(1, bj + 1) - j0,
                      mz = corner_index(2, bk + 1) - k0;  // cells in this brick
      const long long sx = mx + 1, sy = my + 1;
      std::vector<double> v((mx + 1) * (my + 1) * (mz + 1));
      RowSampler& sampler = *samplers[static_cast<size_t>(detail::worker_index())];
      const auto ts = Clock::now();
      for (long long kk = 0; kk <= mz; ++kk)
        for (long long jj = 0; jj <= my; ++jj)
          sampler.sample(i0, sx, j0 + jj, k0 + kk, &v[static_cast<size_t>((kk * sy + jj) * sx)]);
      sampling_seconds += seconds_since(ts);
      samples += static_cast<long long>(v.size());
      for (double val : v) nan_count += std::isnan(val) ? 1 : 0;
      auto& out_t = tris[static_cast<size_t>(q)];
      auto& out_c = cross[static_cast<size_t>(q)];
      for (long long kk = 0; kk < mz; ++kk)
        for (long long jj = 0; jj < my; ++jj)
          for (long long ii = 0; ii < mx; ++ii) {
            double cv[8];
            for (int c = 0; c < 8; ++c) {
              const auto& d = detail::kCorner[c];
              cv[c] = v[static_cast<size_t>(((kk + d[2]) * sy + jj + d[1]) * sx + ii + d[0])];
            }
            int cube_case = 0;
            for (int c = 0; c < 8; ++c) cube_case |= static_cast<int>(is_positive(cv[c])) << c;
            if (cube_case == 0 || cube_case == 255) continue;
            ++active_cells;
            const CellPolygons& polys =
                cell_entry(table, cube_case, [&](int c) { return cv[c]; }, ambiguous);
            std::uint64_t key[12];
            Vec3 pos[12];
            for (unsigned m = detail::kCrossingEdges[static_cast<size_t>(cube_case)]; m; m &= m - 1) {
              const int e = std::countr_zero(m);
              const int c0 = kEdgeCorners[e][0], c1 = kEdgeCorners[e][1];
              const auto& d = detail::kCorner[c0];
              const int a = kEdgeAxis[e];
              const long long gi = i0 + ii + d[0], gj = j0 + jj + d[1], gk = k0 + kk + d[2];
              key[e] = key_of(gi, gj, gk, a);
              pos[e] = linear_point(g, gi, gj, gk, a, cv[c0], cv[c1]);
              out_c.push_back({key[e], {gi, gj, gk, a, cv[c0], cv[c1]}});
            }
            triangulate_cell(
                polys, [&](int e) -> const Vec3& { return pos[e]; },
                [&](int e0, int e1, int e2) { out_t.push_back({key[e0], key[e1], key[e2]}); });
          }
      std::sort(out_c.begin(), out_c.end(),
                [](const KeyedCrossing& l, const KeyedCrossing& r) { return l.key < r.key; });
      out_c.erase(std::unique(out_c.begin(), out_c.end(),
                              [](const KeyedCrossing& l, const KeyedCrossing& r) {
                                return l.key == r.key;
                              }),
                  out_c.end());
    }
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
  all.erase(std::unique(all.begin(), all.end(),
                        [](const KeyedCrossing& l, const KeyedCrossing& r) { return l.key == r.key; }),
            all.end());
  if (all.size() > kMaxVertices)
    throw Error(fmt::format("the mesh would have {} vertices, more than 2^32; lower the "
                            "resolution", all.size()));
  std::vector<std::uint64_t> keys(all.size());
  std::vector<Crossing> crossings(all.size());
  for (size_t n = 0; n < all.size(); ++n) keys[n] = all[n].key, crossings[n] = all[n].c;
  std::vector<KeyedCrossing>().swap(all);

  auto t_ref = Clock::now();
  res.positions.resize(crossings.size());
  {
    std::vector<std::unique_ptr<VertexPlacer>> placers(static_cast<size_t>(workers));
    for (auto& p : placers) p = std::make_unique<VertexPlacer>(surface.field, g, poly, o.refine_steps);
    place_vertices_parallel(placers, workers, crossings, res.positions.data(),
                            st.refine_evaluations, stop);
  }
  st.seconds_refinement += seconds_since(t_ref);
  if (stop.stop_requested()) return {};

  size_t total = 0;
  std::vector<size_t> start(tris.size() + 1, 0);
  for (size_t q = 0; q < tris.size(); ++q) start[q + 1] = start[q] + tris[q].size();
  total = start.back();
  res.triangles.resize(total);
  auto id_of = [&](std::uint64_t key) {
    return static_cast<std::uint32_t>(std::lower_bound(keys.begin(), keys.end(), key) - keys.begin());
  };
#pragma omp parallel for num_threads(workers) schedule(dynamic, 16)
  for (long long q = 0; q < static_cast<long long>(tris.size()); ++q) {
    const auto& src = tris[static_cast<size_t>(q)];
    for (size_t t = 0; t < src.size(); ++t)
      res.triangles[start[static_cast<size_t>(q)] + t] = {id_of(src[t][0]), id_of(src[t][1]),
                                                          id_of(src[t][2])};
  }
  st.active_cells += active_cells;
  st.ambiguous_faces += ambiguous;
  st.edge_vertices += static_cast<long long>(keys.size());
  st.seconds_extraction += seconds_since(t1) - sampling_seconds / workers;
  return res;
}

}  // namespace

GridPlan plan_grid(const Surface& surface, const PolygonizeOptions& options) {
  const Grid g = make_grid(surface, options);
  GridPlan plan;
  plan.cells = g.cells;
  plan.cell_size = g.h;
  plan.box.lo = g.lo;
  plan.box.hi = g.node(g.cells[0], g.cells[1], g.cells[2]);
  plan.sparse = use_sparse(g, options);
  const double nodes =
      static_cast<double>(g.nx()) * static_cast<double>(g.ny()) * static_cast<double>(g.nz());
  // Per estimated triangle: the mesh itself, its construction, and the improver's state.
  const double mesh_bytes = 160.0 * estimate_triangles(g);
  if (plan.sparse) {
    const double B = options.brick_cells;
    plan.estimated_bytes = nodes / (B * B * B) * 40.0 + mesh_bytes;
  } else {
    // Each worker holds F on three node layers (8 bytes a node) and the bit sets and ids of
    // one slab, its node layers plus two (about half a byte a node).
    const double layer_nodes = static_cast<double>(g.nx()) * static_cast<double>(g.ny());
    plan.estimated_bytes = detail::worker_count(options.threads) * layer_nodes *
                               (3 * 8.0 + static_cast<double>(kSlabLayers + 2) * 0.5) +
                           mesh_bytes;
  }
  return plan;
}

Mesh polygonize(const Surface& surface, const PolygonizeOptions& options, PolygonizeStats* stats,
                std::stop_token stop) {
  const auto t_start = Clock::now();
  const Grid g = make_grid(surface, options);
  PolygonizeStats st;
  st.grid_bounds.lo = g.lo;
  st.grid_bounds.hi = g.node(g.cells[0], g.cells[1], g.cells[2]);
  for (int a = 0; a < 3; ++a) st.cells[static_cast<size_t>(a)] = static_cast<int>(g.cells[static_cast<size_t>(a)]);
  st.cell_size = g.h;
  st.sparse = use_sparse(g, options);
  surface.field.require_parameters();
  const int workers = detail::worker_count(options.threads);

  std::optional<Polynomial> poly;
  if (options.polynomial_rows && surface.field.is_expandable()) poly = surface.field.polynomial();

  DenseResult r = st.sparse ? extract_sparse(surface, g, options, poly ? &*poly : nullptr, workers, st, stop)
                            : extract_dense(surface, g, options, poly ? &*poly : nullptr, workers, st, stop);
  if (stop.stop_requested()) return {};

  const auto t_clean = Clock::now();
  Mesh mesh;
  mesh.positions = std::move(r.positions);
  mesh.triangles = std::move(r.triangles);
  mesh.is_boundary.assign(mesh.positions.size(), 0);
  if (clips(surface, options)) {
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
