// Placing one vertex on each crossing edge of the polygonizer: the linear interpolation,
// then refinement on F restricted to the edge (vertex_placement_detail.h).
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include "vertex_placement_detail.h"
#include "zeroset/detail/parallel.h"

namespace zeroset::detail {

// An edge's line comes from the restriction along its axis with v fixed (set_v builds a
// table from all terms of F, the costly part) and a Horner pass in u:
//   x edges: (u, v) = (y, z) and y edges: (u, v) = (x, z), v fixed for a whole node layer;
//   z edges: (u, v) = (x, y), v fixed for a whole xz plane: they are taken by j rather
//   than in row order, so that each plane's table is built once.
void VertexPlacer::place_polynomial(std::span<const Crossing> in, Vec3* out,
                                    long long& evaluations) {
  order_.clear();
  long long j_lo = std::numeric_limits<long long>::max();
  long long j_hi = std::numeric_limits<long long>::min();
  size_t z_count = 0;
  for (size_t n = 0; n < in.size(); ++n)
    if (in[n].axis < 2)
      order_.push_back(static_cast<std::uint32_t>(n));
    else
      ++z_count, j_lo = std::min(j_lo, in[n].j), j_hi = std::max(j_hi, in[n].j);
  if (z_count > 0) {  // the z edges after them, by j (a stable counting sort)
    bucket_.assign(static_cast<size_t>(j_hi - j_lo + 2), 0);
    for (size_t n = 0; n < in.size(); ++n)
      if (in[n].axis == 2) ++bucket_[static_cast<size_t>(in[n].j - j_lo + 1)];
    for (size_t b = 1; b < bucket_.size(); ++b) bucket_[b] += bucket_[b - 1];
    const size_t first = order_.size();
    order_.resize(first + z_count);
    for (size_t n = 0; n < in.size(); ++n)
      if (in[n].axis == 2)
        order_[first + bucket_[static_cast<size_t>(in[n].j - j_lo)]++] =
            static_cast<std::uint32_t>(n);
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
void VertexPlacer::fill_chunk(std::span<const Crossing> in, const std::uint32_t* edge, size_t len) {
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
      const __m256d u =
          _mm256_setr_pd(u_of(f), u_of(std::min(f + 1, end - 1)), u_of(std::min(f + 2, end - 1)),
                         u_of(std::min(f + 3, end - 1)));
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
long long VertexPlacer::refine_block(size_t b, int lanes) {
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
    act[g] =
        steps_ > 0 ? _mm256_and_pd(in_use, _mm256_and_pd(finite(flo[g]), finite(fhi[g]))) : zero;
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
      f[g] =
          _mm256_loadu_pd(C + static_cast<size_t>(degree) * kStride + 4 * static_cast<size_t>(g));
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
long long VertexPlacer::refine_block(size_t b, int lanes) {
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

void VertexPlacer::place_batched(std::span<const Crossing> in, Vec3* out, long long& evaluations,
                                 long long& poles) {
  const size_t n = in.size();
  brackets_.clear();
  t_.resize(n);
  active_.resize(n);
  smallest_.assign(n, std::numeric_limits<double>::infinity());
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
      // NaN compares false: an undefined value never counts as small.
      if (std::abs(f_[q]) < smallest_[e]) smallest_[e] = std::abs(f_[q]);
      if (f_[q] == 0) continue;  // exact root
      bool done = false;
      t_[e] = brackets_[e].next(t_[e], f_[q], done);
      if (!done) active_[kept++] = e;
    }
    active_.resize(kept);
  }
  for (size_t e = 0; e < n; ++e) {
    out[e] = point(in[e], t_[e]);
    // A sign change where |F| does not get smaller is a pole or a jump, not a zero (1/x − 1
    // at x = 0); polynomials have none, so only this path looks. Where |F| did not clearly
    // drop (rare), the vertex must be on F = 0 to first order.
    if (steps_ <= 0 || !finite_ends(in[e].fa, in[e].fb) ||
        clearly_refined(in[e].fa, in[e].fb, smallest_[e]))
      continue;
    Vec3 g;
    const double f = eval_->value_gradient(out[e], g);
    if (f == 0 || std::abs(f) <= kMaxVertexResidual * grid_.h * g.norm()) continue;  // NaN: no
    out[e] = no_vertex();
    ++poles;
  }
}

// Places a batch of crossings split over the workers (chunks of a few thousand edges).
void place_vertices_parallel(std::vector<std::unique_ptr<VertexPlacer>>& placers, int workers,
                             const std::vector<Crossing>& in, Vec3* out, long long& evaluations,
                             long long& poles, const std::stop_token& stop) {
  constexpr size_t kChunk = 4096;
  const long long chunks = static_cast<long long>((in.size() + kChunk - 1) / kChunk);
  long long evals = 0, refused = 0;
  detail::ExceptionTrap trap;
#pragma omp parallel for num_threads(workers) schedule(dynamic, 1) reduction(+ : evals, refused)
  for (long long c = 0; c < chunks; ++c)
    trap.run([&] {
      if (stop.stop_requested()) return;
      const size_t b = static_cast<size_t>(c) * kChunk, e = std::min(in.size(), b + kChunk);
      placers[static_cast<size_t>(worker_index())]->place(
          std::span<const Crossing>(in.data() + b, e - b), out + b, evals, refused);
    });
  trap.rethrow();
  evaluations += evals;
  poles += refused;
}

}  // namespace zeroset::detail
