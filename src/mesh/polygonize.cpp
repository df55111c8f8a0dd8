#include "zeroset/mesh/polygonize.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include <fmt/core.h>

#if defined(__AVX__)
#include <immintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "mc_table_detail.h"
#include "parallel_detail.h"
#include "mesh_detail.h"
#include "zeroset/error.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/mesh/mesh_ops.h"

namespace zeroset {
namespace {

using Clock = std::chrono::steady_clock;
using detail::CellPolygons;
using detail::kEdgeAxis;
using detail::kEdgeCorners;
using detail::kFaceCanonical;

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
// polynomial in u whose coefficients depend on v alone; those are kept for the last v, since
// callers walk lines with v fixed (a layer of rows, the edges of one row), so a line then
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

  /// c[0..degree] of F along the line through (u, v).
  void coefficients(double u, double v, double* c) {
    const size_t n = static_cast<size_t>(degree_ + 1);
    if (!have_v_ || v != v_) {
      v_powers_[0] = 1;
      for (size_t a = 1; a < n; ++a) v_powers_[a] = v_powers_[a - 1] * v;
      std::fill(in_u_.begin(), in_u_.end(), 0.0);
      for (const Term& m : terms_)
        in_u_[static_cast<size_t>(m.t) * n + static_cast<size_t>(m.u)] +=
            m.c * v_powers_[static_cast<size_t>(m.v)];
      v_ = v, have_v_ = true;
    }
    for (size_t m = 0; m < n; ++m) {
      const double* d = &in_u_[m * n];
      double sum = d[n - 1 - m];  // u's degree in the t^m coefficient is at most degree − m
      for (size_t a = n - 1 - m; a-- > 0;) sum = sum * u + d[a];
      c[m] = sum;
    }
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

// Samples F at runs of grid nodes along x: through the line restriction for polynomials
// (vectorised Horner), otherwise through the field over structure-of-arrays rows.
class RowSampler {
 public:
  RowSampler(const Field& field, const Grid& grid, const Polynomial* poly)
      : eval_(field), grid_(grid) {
    if (!poly) return;
    line_.emplace(*poly, grid, 0);
    coeffs_.resize(static_cast<size_t>(std::max(0, line_->degree()) + 1));
    t_.resize(static_cast<size_t>(grid_.nx()));
    for (long long i = 0; i < grid_.nx(); ++i) t_[static_cast<size_t>(i)] = line_->t_of(i);
  }

  void sample(long long i0, long long count, long long j, long long k, double* out) {
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
      // Four independent chains of four nodes hide the latency of the multiply-adds.
      for (; n + 16 <= count; n += 16) {
        __m256d acc[4], tt[4];
        for (int q = 0; q < 4; ++q) acc[q] = _mm256_set1_pd(c[degree]), tt[q] = _mm256_loadu_pd(t + n + 4 * q);
        for (int m = degree - 1; m >= 0; --m) {
          const __m256d cm = _mm256_set1_pd(c[m]);
          for (int q = 0; q < 4; ++q) acc[q] = _mm256_fmadd_pd(acc[q], tt[q], cm);
        }
        for (int q = 0; q < 4; ++q) _mm256_storeu_pd(out + n + 4 * q, acc[q]);
      }
      for (; n < count; ++n) {
        double v = c[degree];
        for (int m = degree - 1; m >= 0; --m) v = std::fma(v, t[n], c[m]);
        out[n] = v;
      }
#else
      for (; n < count; ++n) {
        double v = c[degree];
        for (int m = degree - 1; m >= 0; --m) v = v * t[n] + c[m];
        out[n] = v;
      }
#endif
      return;
    }
    if (line_) {  // the zero polynomial
      std::fill(out, out + count, 0.0);
      return;
    }
    x_.resize(static_cast<size_t>(count));
    y_.assign(static_cast<size_t>(count), grid_.coord(1, j));
    z_.assign(static_cast<size_t>(count), grid_.coord(2, k));
    for (long long n = 0; n < count; ++n) x_[static_cast<size_t>(n)] = grid_.coord(0, i0 + n);
    eval_.values(x_, y_, z_, std::span<double>(out, static_cast<size_t>(count)));
  }

 private:
  Evaluator eval_;
  const Grid& grid_;
  std::optional<LineRestriction> line_;
  std::vector<double> coeffs_, t_, x_, y_, z_;
};

bool is_positive(double v) { return !(v < 0); }  // NaN counts as positive

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

// The Illinois variant of regula falsi on one edge, in the edge's fraction s ∈ [0, 1]: the
// bracket [lo, hi] keeps opposite signs, and the end value kept twice in a row is halved so
// the bracket shrinks from both sides. Robust where the surface touches the edge (a double
// root), where Newton's method would crawl.
struct IllinoisBracket {
  double lo = 0, hi = 1, f_lo = 0, f_hi = 0;
  int last_side = 0;

  IllinoisBracket() = default;
  IllinoisBracket(double fa, double fb) : f_lo(fa), f_hi(fb) {}

  /// Takes F at s (not 0) and returns the next s; sets `done` once s no longer moves.
  double next(double s, double f, bool& done) {
    if (is_positive(f) == is_positive(f_hi)) {
      hi = s, f_hi = f;
      if (last_side == 1) f_lo *= 0.5;
      last_side = 1;
    } else {
      lo = s, f_lo = f;
      if (last_side == -1) f_hi *= 0.5;
      last_side = -1;
    }
    // Converged, the estimate may round onto the end just set (s): that ends the search,
    // so only an estimate outside the closed bracket falls back to bisection.
    double n = hi - f_hi * (hi - lo) / (f_hi - f_lo);
    if (!std::isfinite(n) || n < std::min(lo, hi) || n > std::max(lo, hi)) n = 0.5 * (lo + hi);
    done = std::abs(n - s) <= 1e-13 || std::abs(hi - lo) <= 1e-15;
    return n;
  }
};

// Places one vertex on each crossing edge: linear interpolation, then refinement on F
// restricted to the edge by the Illinois method. Polynomials: F along the edge is a
// univariate polynomial (its grid line's restriction), so each step is one Horner
// evaluation. Other fields: all edges of a batch are evaluated together through the
// field's tape. One per worker.
class VertexPlacer {
 public:
  VertexPlacer(const Field& field, const Grid& grid, const Polynomial* poly, int steps)
      : eval_(field), grid_(grid), steps_(steps) {
    if (!poly || poly->degree() < 1) return;
    for (int a = 0; a < 3; ++a) lines_[static_cast<size_t>(a)].emplace(*poly, grid, a);
    coeffs_.resize(static_cast<size_t>(poly->degree() + 1));
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

  // Edges go through in blocks of kLanes, refined in lockstep: each step is a chain of
  // dependent multiply-adds and a division, so independent edges side by side keep the
  // processor busy (and the Horner loop vectorises across lanes). Finished lanes stay put.
  static constexpr int kLanes = 8;

  void place_polynomial(std::span<const Crossing> in, Vec3* out, long long& evaluations) {
    const int degree = lines_[0]->degree();
    const size_t nc = static_cast<size_t>(degree + 1);
    lane_coeffs_.resize(nc * kLanes);  // [m · kLanes + lane]
    double* C = lane_coeffs_.data();
    long long have[3] = {-1, -1, -1};  // the line whose coefficients are in coeffs_
    int have_axis = -1;
    for (size_t b = 0; b < in.size(); b += kLanes) {
      const int lanes = static_cast<int>(std::min<size_t>(kLanes, in.size() - b));
      double s[kLanes], t0[kLanes];
      bool active[kLanes];
      std::array<IllinoisBracket, kLanes> bracket;
      int running = 0;
      for (int q = 0; q < kLanes; ++q) {
        const Crossing& x = in[b + static_cast<size_t>(q < lanes ? q : 0)];
        s[q] = linear_fraction(x.fa, x.fb);
        t0[q] = 0;
        active[q] = q < lanes && steps_ > 0 && std::isfinite(x.fa) && std::isfinite(x.fb);
        if (!active[q]) {
          for (size_t m = 0; m < nc; ++m) C[m * kLanes + static_cast<size_t>(q)] = 0;
          continue;
        }
        // The other two grid indices fix the line; consecutive x edges share it.
        const long long idx[3] = {x.i, x.j, x.k};
        const int ua = x.axis == 0 ? 1 : 0, va = x.axis == 2 ? 1 : 2;
        LineRestriction& line = *lines_[static_cast<size_t>(x.axis)];
        if (x.axis != have_axis || idx[ua] != have[ua] || idx[va] != have[va]) {
          line.coefficients(grid_.coord(ua, idx[ua]), grid_.coord(va, idx[va]), coeffs_.data());
          have[0] = x.i, have[1] = x.j, have[2] = x.k, have_axis = x.axis;
        }
        for (size_t m = 0; m < nc; ++m) C[m * kLanes + static_cast<size_t>(q)] = coeffs_[m];
        t0[q] = line.t_of(idx[x.axis]);
        bracket[static_cast<size_t>(q)] = IllinoisBracket(x.fa, x.fb);
        ++running;
      }
#if defined(__AVX2__) && defined(__FMA__)
      if (running > 0) evaluations += illinois_lanes_avx(C, degree, t0, bracket, active, s);
#else
      for (int it = 0; it < steps_ && running > 0; ++it) {
        double f[kLanes], t[kLanes];
        for (int q = 0; q < kLanes; ++q) t[q] = t0[q] + s[q], f[q] = C[static_cast<size_t>(degree) * kLanes + static_cast<size_t>(q)];
        for (int m = degree - 1; m >= 0; --m)
          for (int q = 0; q < kLanes; ++q) f[q] = f[q] * t[q] + C[static_cast<size_t>(m) * kLanes + static_cast<size_t>(q)];
        for (int q = 0; q < kLanes; ++q) {
          if (!active[q]) continue;
          ++evaluations;
          bool done = f[q] == 0 || !std::isfinite(f[q]);
          if (!done) s[q] = bracket[static_cast<size_t>(q)].next(s[q], f[q], done);
          if (done) active[q] = false, --running;
        }
      }
#endif
      for (int q = 0; q < lanes; ++q) out[b + static_cast<size_t>(q)] = point(in[b + static_cast<size_t>(q)], s[q]);
    }
  }

#if defined(__AVX2__) && defined(__FMA__)
  // The lockstep iteration above, four lanes per vector: IllinoisBracket::next with masks
  // instead of branches, the same operations in the same order, so vertices are bit-identical
  // to the scalar loop's. Returns the evaluations of active lanes.
  long long illinois_lanes_avx(const double* C, int degree, const double* t0,
                               const std::array<IllinoisBracket, kLanes>& bracket,
                               const bool* active, double* s) const {
    static_assert(kLanes % 4 == 0);
    long long evaluations = 0;
    for (int g = 0; g < kLanes; g += 4) {
      double lo_[4], hi_[4], flo_[4], fhi_[4], last_[4], act_[4];
      for (int q = 0; q < 4; ++q) {
        const IllinoisBracket& br = bracket[static_cast<size_t>(g + q)];
        lo_[q] = br.lo, hi_[q] = br.hi, flo_[q] = br.f_lo, fhi_[q] = br.f_hi;
        last_[q] = br.last_side;
        act_[q] = active[g + q] ? -1.0 : 0.0;  // a set sign bit marks an active lane
      }
      __m256d lo = _mm256_loadu_pd(lo_), hi = _mm256_loadu_pd(hi_);
      __m256d flo = _mm256_loadu_pd(flo_), fhi = _mm256_loadu_pd(fhi_);
      __m256d last = _mm256_loadu_pd(last_), sv = _mm256_loadu_pd(s + g);
      __m256d act = _mm256_cmp_pd(_mm256_loadu_pd(act_), _mm256_setzero_pd(), _CMP_LT_OQ);
      const __m256d tg = _mm256_loadu_pd(t0 + g);
      const __m256d zero = _mm256_setzero_pd(), half = _mm256_set1_pd(0.5);
      const __m256d one = _mm256_set1_pd(1.0), minus_one = _mm256_set1_pd(-1.0);
      const __m256d abs_mask = _mm256_castsi256_pd(_mm256_set1_epi64x(0x7fffffffffffffffLL));
      auto finite = [&](__m256d x) { return _mm256_cmp_pd(_mm256_sub_pd(x, x), zero, _CMP_EQ_OQ); };
      for (int it = 0; it < steps_; ++it) {
        const int mask = _mm256_movemask_pd(act);
        if (!mask) break;
        evaluations += std::popcount(static_cast<unsigned>(mask));
        const __m256d t = _mm256_add_pd(tg, sv);
        __m256d f = _mm256_loadu_pd(C + static_cast<size_t>(degree) * kLanes + static_cast<size_t>(g));
        for (int m = degree - 1; m >= 0; --m)
          f = _mm256_fmadd_pd(f, t, _mm256_loadu_pd(C + static_cast<size_t>(m) * kLanes + static_cast<size_t>(g)));
        // An exact root or a non-finite value ends the lane where it is.
        const __m256d stop = _mm256_or_pd(_mm256_cmp_pd(f, zero, _CMP_EQ_OQ),
                                          _mm256_andnot_pd(finite(f), act));
        const __m256d step = _mm256_andnot_pd(stop, act);
        // Which end s replaces: the one whose value has f's sign (is_positive alike).
        const __m256d same = _mm256_xor_pd(
            _mm256_xor_pd(_mm256_cmp_pd(f, zero, _CMP_NLT_UQ), _mm256_cmp_pd(fhi, zero, _CMP_NLT_UQ)),
            _mm256_castsi256_pd(_mm256_set1_epi64x(-1)));
        const __m256d up = _mm256_and_pd(step, same), down = _mm256_andnot_pd(same, step);
        const __m256d halve_lo = _mm256_and_pd(up, _mm256_cmp_pd(last, one, _CMP_EQ_OQ));
        const __m256d halve_hi = _mm256_and_pd(down, _mm256_cmp_pd(last, minus_one, _CMP_EQ_OQ));
        flo = _mm256_blendv_pd(flo, _mm256_mul_pd(flo, half), halve_lo);
        fhi = _mm256_blendv_pd(fhi, _mm256_mul_pd(fhi, half), halve_hi);
        hi = _mm256_blendv_pd(hi, sv, up), fhi = _mm256_blendv_pd(fhi, f, up);
        lo = _mm256_blendv_pd(lo, sv, down), flo = _mm256_blendv_pd(flo, f, down);
        last = _mm256_blendv_pd(_mm256_blendv_pd(last, minus_one, down), one, up);
        __m256d n = _mm256_sub_pd(hi, _mm256_div_pd(_mm256_mul_pd(fhi, _mm256_sub_pd(hi, lo)),
                                                    _mm256_sub_pd(fhi, flo)));
        const __m256d outside = _mm256_or_pd(
            _mm256_andnot_pd(finite(n), step),
            _mm256_or_pd(_mm256_cmp_pd(n, _mm256_min_pd(lo, hi), _CMP_LT_OQ),
                         _mm256_cmp_pd(n, _mm256_max_pd(lo, hi), _CMP_GT_OQ)));
        n = _mm256_blendv_pd(n, _mm256_mul_pd(half, _mm256_add_pd(lo, hi)), outside);
        const __m256d done = _mm256_or_pd(
            _mm256_cmp_pd(_mm256_and_pd(_mm256_sub_pd(n, sv), abs_mask), _mm256_set1_pd(1e-13), _CMP_LE_OQ),
            _mm256_cmp_pd(_mm256_and_pd(_mm256_sub_pd(hi, lo), abs_mask), _mm256_set1_pd(1e-15), _CMP_LE_OQ));
        sv = _mm256_blendv_pd(sv, n, step);
        act = _mm256_andnot_pd(_mm256_or_pd(stop, _mm256_and_pd(done, step)), act);
      }
      _mm256_storeu_pd(s + g, sv);
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
      eval_.values(x_, y_, z_, f_);
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

  Evaluator eval_;
  const Grid& grid_;
  int steps_;
  std::array<std::optional<LineRestriction>, 3> lines_;
  std::vector<double> coeffs_, lane_coeffs_;
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

// Triangulates a cycle of edge points (n ≤ 12) to maximise the smallest triangle quality
// (mean ratio 4√3·area / Σ edge²), never using a diagonal between two points of one cube
// face: such a diagonal could also appear in the neighbouring cube and make the edge
// non-manifold. Emits triangles in cycle order (counter-clockwise seen from F > 0).
template <class Emit>
void triangulate_cycle(const std::uint8_t* edges, int n, const Vec3* pos, Emit&& emit) {
  if (n == 3) {
    emit(edges[0], edges[1], edges[2]);
    return;
  }
  // Squared distances between the cycle's points, computed once: every triangle's quality
  // comes from its three sides.
  double d2[12][12];
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) d2[a][b] = (pos[edges[b]] - pos[edges[a]]).squaredNorm();
  // The square of the quality up to a constant factor (it orders triangles alike): with sides
  // u = b − a, v = c − a, |u × v|² = |u|²|v|² − (u·v)² and 2 u·v = |u|² + |v|² − |c − b|².
  auto quality = [&](int a, int b, int c) {  // a < b < c
    const double u = d2[a][b], v = d2[a][c], w = d2[b][c];
    const double dot = 0.5 * (u + v - w);
    const double area2 = std::max(0.0, u * v - dot * dot);
    const double sum = u + v + w;
    return sum > 0 ? area2 / (sum * sum) : 0.0;
  };
  auto allowed = [&](int a, int b) {
    return b - a == 1 || (a == 0 && b == n - 1) ||
           !detail::edges_share_face(edges[a], edges[b]);
  };
  if (n == 4) {  // the most common cycle: two diagonals, decided as the general case would
    const double via1 = allowed(1, 3) ? std::min(quality(0, 1, 3), quality(1, 2, 3)) : -1;
    const double via2 = allowed(0, 2) ? std::min(quality(0, 2, 3), quality(0, 1, 2)) : -1;
    if (via2 > via1) emit(edges[0], edges[2], edges[3]), emit(edges[0], edges[1], edges[2]);
    else emit(edges[0], edges[1], edges[3]), emit(edges[1], edges[2], edges[3]);
    return;
  }
  bool ok[12][12];
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) ok[a][b] = allowed(a, b);
  double best[12][12];
  int split[12][12];
  for (int len = 2; len < n; ++len)
    for (int a = 0; a + len < n; ++a) {
      const int b = a + len;
      best[a][b] = -2;
      split[a][b] = -1;
      for (int m = a + 1; m < b; ++m) {
        double s = ok[a][m] && ok[m][b] ? quality(a, m, b) : -1;
        if (m - a > 1) s = std::min(s, best[a][m]);
        if (b - m > 1) s = std::min(s, best[m][b]);
        if (s > best[a][b]) best[a][b] = s, split[a][b] = m;
      }
    }
  // Explicit stack: (a, b) sub-polygons still to split.
  int stack_a[12], stack_b[12], top = 0;
  stack_a[top] = 0, stack_b[top] = n - 1, ++top;
  while (top > 0) {
    --top;
    const int a = stack_a[top], b = stack_b[top];
    const int m = split[a][b];
    emit(edges[a], edges[m], edges[b]);
    if (m - a > 1) stack_a[top] = a, stack_b[top] = m, ++top;
    if (b - m > 1) stack_a[top] = m, stack_b[top] = b, ++top;
  }
}

// The cube's case, its face decisions and its cycles.
struct CellCase {
  int cube_case = 0;
  int ambiguous = 0;
  const CellPolygons* polys = nullptr;
};

// `table` is detail::cell_polygon_table(), looked up once by the caller's loop.
CellCase classify_cell(const double v[8], const CellPolygons* table) {
  CellCase c;
  for (int k = 0; k < 8; ++k) c.cube_case |= static_cast<int>(is_positive(v[k])) << k;
  const int amb = detail::ambiguous_faces(c.cube_case);
  int connected = 0;
  if (amb) {  // rare: decide each ambiguous face
    for (int f = 0; f < 6; ++f) {
      if (!((amb >> f) & 1)) continue;
      const auto& q = kFaceCanonical[f];
      if (detail::positive_corners_connected(v[q[0]], v[q[1]], v[q[2]], v[q[3]]))
        connected |= 1 << f;
    }
    c.ambiguous = std::popcount(static_cast<unsigned>(amb));
  }
  c.polys = &table[c.cube_case * 64 + connected];
  return c;
}

// Emits the triangles of one cell given the vertex handles and positions of its 12 edges.
template <class Handle, class Out>
void emit_cell(const CellPolygons& polys, const Handle* handle, const Vec3* pos, Out& out) {
  int offset = 0;
  for (int c = 0; c < polys.cycle_count; ++c) {
    const int n = polys.cycle_length[c];
    triangulate_cycle(&polys.edges[offset], n, pos, [&](int e0, int e1, int e2) {
      out.push_back({handle[e0], handle[e1], handle[e2]});
    });
    offset += n;
  }
}

using Triangle = std::array<std::uint32_t, 3>;

// ---------------------------------------------------------------------------------------
// Dense path: every node sampled; vertex ids from per-row prefix counts over bit sets.
//
// The grid is cut into slabs of a few cell layers (slab_layers), handled one at a time by a worker
// from sampling to triangles, so only a slab's values are held (not the whole volume) and
// they are still in cache when its triangles are made. Vertices are numbered in row order
// (row = (j, k), then axis, then x), the same order whatever the slabs: a slab numbers the
// rows of its own node layers from 0 and carries on into the next slab's first layer (the
// top faces of its last cells), so adding the slab's first global id makes all its ids
// global. That numbering needs the z edges of that layer, so a slab samples two node
// layers beyond its own. Slab sizes depend on the grid only, so the mesh does not depend on the
// thread count.

struct DenseResult {
  std::vector<Vec3> positions;
  std::vector<Triangle> triangles;
};

constexpr long long kSlabLayers = 16;

// Cell layers per slab: kSlabLayers, fewer on small grids so that they still make eight slabs
// for the workers to share (never fewer than 8 layers: each slab samples two extra layers).
long long slab_layers(const Grid& g) { return std::clamp<long long>(g.cells[2] / 8, 8, kSlabLayers); }

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

// What one slab made, with slab-local vertex ids.
struct Slab {
  std::vector<Vec3> positions;  // the vertices of the slab's own node layers
  std::vector<Triangle> triangles;
  std::uint64_t numbered = 0;   // vertices numbered, including the next slab's first layer
  long long active_cells = 0, ambiguous = 0, samples = 0, nan_samples = 0, evaluations = 0;
  double seconds_sampling = 0, seconds_refinement = 0;
};

// A worker's arrays, reused from slab to slab (resized, never cleared: every entry used is
// written first).
struct SlabScratch {
  std::vector<double> values;
  std::vector<std::uint64_t> positive, crossing_bits;
  std::vector<std::uint32_t> first_id;
  std::vector<Crossing> crossings;
  std::vector<Vec3> linear;
};

// Samples, numbers and triangulates the cells of layers [k0, k0 + layers).
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

  // Sample F row by row, then its sign bits a word at a time.
  const auto ts = Clock::now();
  std::vector<double>& V = scratch.values;
  std::vector<std::uint64_t>& P = scratch.positive;
  V.resize(static_cast<size_t>(nx * rows));
  P.resize(static_cast<size_t>(W * rows));
  for (long long r = 0; r < rows; ++r) {
    double* row = &V[static_cast<size_t>(r * nx)];
    sampler.sample(0, nx, r % ny, k0 + r / ny, row);
    std::uint64_t* bits = &P[static_cast<size_t>(r * W)];
    const long long nans = sign_bits(row, nx, bits);
    if (r < own_rows) slab.nan_samples += nans;
  }
  slab.samples += nx * rows;
  slab.seconds_sampling += seconds_since(ts);

  // Crossing bits per (row, axis, word), and the id of the first crossing of each: a
  // crossing's id is its word's first id plus the crossings before it in the word.
  std::vector<std::uint64_t>& C = scratch.crossing_bits;
  std::vector<std::uint32_t>& off = scratch.first_id;
  C.resize(static_cast<size_t>(num_rows * 3 * W));
  off.resize(C.size());
  const std::uint64_t last_node_mask = (nx % 64) ? (1ull << (nx % 64)) - 1 : ~0ull;
  const std::uint64_t last_edge_mask =
      ((nx - 1) % 64) ? (1ull << ((nx - 1) % 64)) - 1 : ~0ull;  // x edges: i ≤ nx − 2
  const long long edge_words = (nx - 1 + 63) / 64;
  std::uint64_t id = 0, own_count = 0;
  for (long long r = 0; r < num_rows; ++r) {
    const long long j = r % ny, k = k0 + r / ny;
    const std::uint64_t* p = &P[static_cast<size_t>(r * W)];
    std::uint64_t* c = &C[static_cast<size_t>(r * 3 * W)];
    if (r == own_rows) own_count = id;
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
      o[w] = static_cast<std::uint32_t>(id);
      id += static_cast<std::uint64_t>(std::popcount(c[w]));
    }
    if (id > kMaxVertices) {  // the caller reports it
      slab.numbered = id;
      return;
    }
  }
  if (num_rows == own_rows) own_count = id;
  slab.numbered = id;

  // The linear point of every numbered crossing, in id order (the cells use those); then the
  // vertices of the own layers, refined in one batch (without refinement: the linear points).
  const auto tr = Clock::now();
  std::vector<Vec3>& linear = scratch.linear;
  std::vector<Crossing>& crossings = scratch.crossings;
  linear.resize(id);
  crossings.clear();
  const bool refine = placer.refines();
  if (refine) crossings.reserve(own_count);
  {
    const long long stride[3] = {1, nx, nx * ny};
    size_t n = 0;
    for (long long r = 0; r < num_rows; ++r) {
      const long long j = r % ny, k = k0 + r / ny;
      const std::uint64_t* c = &C[static_cast<size_t>(r * 3 * W)];
      for (int a = 0; a < 3; ++a)
        for (long long w = 0; w < W; ++w)
          for (std::uint64_t b = c[a * W + w]; b; b &= b - 1, ++n) {
            const long long i = w * 64 + std::countr_zero(b);
            const long long at = r * nx + i;
            const double fa = V[static_cast<size_t>(at)], fb = V[static_cast<size_t>(at + stride[a])];
            linear[n] = linear_point(g, i, j, k, a, fa, fb);
            if (refine && n < own_count) crossings.push_back({i, j, k, a, fa, fb});
          }
    }
    slab.positions.resize(own_count);
    if (refine) placer.place(crossings, slab.positions.data(), slab.evaluations);
    else std::copy(linear.begin(), linear.begin() + static_cast<long>(own_count), slab.positions.begin());
  }
  slab.seconds_refinement += seconds_since(tr);

  // Triangles of the slab's cells, cell row by cell row.
  const CellPolygons* table = detail::cell_polygon_table();
  const std::uint64_t last_cell_mask = last_edge_mask;
  const long long cell_words = edge_words;
  for (long long k = k0; k < k_cells; ++k)
    for (long long j = 0; j + 1 < ny; ++j) {
      // Node rows of corners (dy, dz) = (0,0), (1,0), (0,1), (1,1).
      const long long r0 = j + ny * (k - k0);
      const long long nr[4] = {r0, r0 + 1, r0 + ny, r0 + ny + 1};
      const double* vr[4];
      for (int q = 0; q < 4; ++q) vr[q] = &V[static_cast<size_t>(nr[q] * nx)];
      for (long long w = 0; w < cell_words; ++w) {
        std::uint64_t all = ~0ull, any = 0;
        for (int q = 0; q < 4; ++q) {
          const std::uint64_t* p = &P[static_cast<size_t>(nr[q] * W)];
          const std::uint64_t next = w + 1 < W ? p[w + 1] : 0;
          const std::uint64_t s = (p[w] >> 1) | (next << 63);
          all &= p[w] & s;
          any |= p[w] | s;
        }
        std::uint64_t act = any & ~all;
        if (w == cell_words - 1) act &= last_cell_mask;
        while (act) {
          const long long i = w * 64 + std::countr_zero(act);
          act &= act - 1;
          // Corner c at (i + dx, j + dy, k + dz), Lorensen numbering.
          double v[8];
          for (int c = 0; c < 8; ++c) v[c] = vr[kCornerRow[c]][i + detail::kCorner[c][0]];
          const CellCase cc = classify_cell(v, table);
          ++slab.active_cells;
          slab.ambiguous += cc.ambiguous;
          std::uint32_t ids[12];
          Vec3 pos[12];
          for (unsigned m = detail::kCrossingEdges[static_cast<size_t>(cc.cube_case)]; m; m &= m - 1) {
            const int e = std::countr_zero(m);
            const long long ii = i + kEdgeDx[e];
            const size_t at = static_cast<size_t>((nr[kEdgeRow[e]] * 3 + kEdgeAxis[e]) * W + (ii >> 6));
            ids[e] = off[at] + static_cast<std::uint32_t>(std::popcount(C[at] & ((1ull << (ii & 63)) - 1)));
            pos[e] = linear[ids[e]];
          }
          emit_cell(*cc.polys, ids, pos, slab.triangles);
        }
      }
    }
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
    std::vector<Triangle>().swap(slab.triangles);
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
            bool any = false, all = true;
            for (double val : cv) {
              const bool p = is_positive(val);
              any |= p, all &= p;
            }
            if (!any || all) continue;
            const CellCase cc = classify_cell(cv, table);
            ++active_cells;
            ambiguous += cc.ambiguous;
            std::uint64_t key[12];
            Vec3 pos[12];
            for (unsigned m = detail::kCrossingEdges[static_cast<size_t>(cc.cube_case)]; m; m &= m - 1) {
              const int e = std::countr_zero(m);
              const int c0 = kEdgeCorners[e][0], c1 = kEdgeCorners[e][1];
              const auto& d = detail::kCorner[c0];
              const int a = kEdgeAxis[e];
              const long long gi = i0 + ii + d[0], gj = j0 + jj + d[1], gk = k0 + kk + d[2];
              key[e] = key_of(gi, gj, gk, a);
              pos[e] = linear_point(g, gi, gj, gk, a, cv[c0], cv[c1]);
              out_c.push_back({key[e], {gi, gj, gk, a, cv[c0], cv[c1]}});
            }
            emit_cell(*cc.polys, key, pos, out_t);
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
    // Each worker holds one slab: its node layers plus two, 8 bytes of F and about half a
    // byte of bit sets and ids per node.
    const double slab_nodes = static_cast<double>(kSlabLayers + 2) *
                              static_cast<double>(g.nx()) * static_cast<double>(g.ny());
    plan.estimated_bytes =
        detail::worker_count(options.threads) * slab_nodes * (8.0 + 0.5) + mesh_bytes;
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
  if (options.polynomial_rows && surface.field.is_polynomial()) poly = surface.field.polynomial();

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
