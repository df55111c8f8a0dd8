#pragma once
// The triangulation of a marching-cubes cell's cycles of edge points, shared by the dense and
// the sparse path of the polygonizer (and its tests).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#if defined(__AVX2__) && defined(__FMA__)
#include <immintrin.h>
#endif

#include "mc_table_detail.h"
#include "zeroset/types.h"

namespace zeroset::detail {

// a·b + c, fused where the processor has fused multiply-adds. Scalar code that must give the
// same bits as the vector code next to it uses this, since the vector code fuses.
inline double madd(double a, double b, double c) {
#if defined(__FMA__)
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

// Triangulation of the cycles. A cycle of n edge points is split into n − 2 triangles that
// maximise the smallest triangle quality (mean ratio 4√3·area / Σ edge²), never with a chord
// between two points of one cube face (CellPolygons::chords): such a chord could also appear
// in the neighbouring cube and make the edge non-manifold. Triangles are emitted in cycle
// order (counter-clockwise seen from F > 0). The polygonizer passes the linear interpolations
// of the crossings (its linear_point), so both of its paths make the same choices.

// The square of a triangle's quality up to a constant factor (it orders triangles alike),
// from its squared sides: with sides u = b − a, v = c − a, |u × v|² = |u|²|v|² − (u·v)² and
// 2 u·v = |u|² + |v|² − |c − b|².
inline double triangle_quality(double u, double v, double w) {
  const double dot = 0.5 * (u + v - w);
  const double area2 = std::max(0.0, madd(u, v, -(dot * dot)));
  const double sum = u + v + w;
  return sum > 0 ? area2 / (sum * sum) : 0.0;
}

// The two ways to split a quadrilateral p0 p1 p2 p3: the worse triangle of (0,1,3), (1,2,3)
// (diagonal 1–3) and of (0,2,3), (0,1,2) (diagonal 0–2).
inline std::array<double, 2> quad_splits(const Vec3& p0, const Vec3& p1, const Vec3& p2,
                                         const Vec3& p3) {
#if defined(__AVX2__) && defined(__FMA__)
  // The four triangles side by side, with the operations of triangle_quality.
  const __m256d x = _mm256_setr_pd(p0.x(), p1.x(), p2.x(), p3.x());
  const __m256d y = _mm256_setr_pd(p0.y(), p1.y(), p2.y(), p3.y());
  const __m256d z = _mm256_setr_pd(p0.z(), p1.z(), p2.z(), p3.z());
  auto squared = [](__m256d dx, __m256d dy, __m256d dz) {
    return _mm256_fmadd_pd(dz, dz, _mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)));
  };
  // Squared sides 0–1, 1–2, 2–3, 3–0 and diagonals 0–2, 1–3, 0–2, 1–3 (a difference and its
  // negative square alike).
  const __m256d side = squared(_mm256_sub_pd(_mm256_permute4x64_pd(x, 0x39), x),
                               _mm256_sub_pd(_mm256_permute4x64_pd(y, 0x39), y),
                               _mm256_sub_pd(_mm256_permute4x64_pd(z, 0x39), z));
  const __m256d diag = squared(_mm256_sub_pd(_mm256_permute4x64_pd(x, 0x4e), x),
                               _mm256_sub_pd(_mm256_permute4x64_pd(y, 0x4e), y),
                               _mm256_sub_pd(_mm256_permute4x64_pd(z, 0x4e), z));
  // Triangles (0,1,3), (1,2,3), (0,2,3), (0,1,2): sides u = a–b, v = a–c, w = b–c.
  const __m256d u = _mm256_blend_pd(_mm256_permute4x64_pd(side, 0x04), diag, 0b0100);
  const __m256d v =
      _mm256_blend_pd(_mm256_permute4x64_pd(side, 0xff), _mm256_permute4x64_pd(diag, 0x04), 0b1010);
  const __m256d w =
      _mm256_blend_pd(_mm256_permute4x64_pd(side, 0x68), _mm256_permute_pd(diag, 0b0101), 0b0001);
  const __m256d uv = _mm256_add_pd(u, v);
  const __m256d dot = _mm256_mul_pd(_mm256_set1_pd(0.5), _mm256_sub_pd(uv, w));
  const __m256d area2 =
      _mm256_max_pd(_mm256_fmsub_pd(u, v, _mm256_mul_pd(dot, dot)), _mm256_setzero_pd());
  const __m256d sum = _mm256_add_pd(uv, w);
  const __m256d q = _mm256_and_pd(_mm256_cmp_pd(sum, _mm256_setzero_pd(), _CMP_GT_OQ),
                                  _mm256_div_pd(area2, _mm256_mul_pd(sum, sum)));
  const __m256d worst = _mm256_min_pd(q, _mm256_permute_pd(q, 0b0101));
  return {_mm256_cvtsd_f64(worst), _mm_cvtsd_f64(_mm256_extractf128_pd(worst, 1))};
#else
  const double d01 = (p1 - p0).squaredNorm(), d12 = (p2 - p1).squaredNorm(),
               d23 = (p3 - p2).squaredNorm(), d03 = (p3 - p0).squaredNorm(),
               d02 = (p2 - p0).squaredNorm(), d13 = (p3 - p1).squaredNorm();
  return {std::min(triangle_quality(d01, d03, d13), triangle_quality(d12, d13, d23)),
          std::min(triangle_quality(d02, d03, d23), triangle_quality(d01, d02, d12))};
#endif
}

template <class Pos, class Emit>
void triangulate_pentagon(const std::uint8_t* edges, const std::uint16_t* chords, Pos& pos,
                          Emit& emit);
template <class Pos, class Emit>
void triangulate_polygon(const std::uint8_t* edges, const std::uint16_t* chords, int n, Pos& pos,
                         Emit& emit);

// `pos(e)` is the point on cube edge e, `emit(e0, e1, e2)` takes a triangle of cube edges.
template <class Pos, class Emit>
void triangulate_cycle(const std::uint8_t* edges, const std::uint16_t* chords, int n, Pos& pos,
                       Emit& emit) {
  if (n == 3) {
    emit(edges[0], edges[1], edges[2]);
    return;
  }
  if (n == 4) {  // the most common cycle: two diagonals, decided as the general case would
    const auto splits = quad_splits(pos(edges[0]), pos(edges[1]), pos(edges[2]), pos(edges[3]));
    const double via1 = (chords[1] >> 3) & 1 ? splits[0] : -1;
    const double via2 = (chords[0] >> 2) & 1 ? splits[1] : -1;
    if (via2 > via1)
      emit(edges[0], edges[2], edges[3]), emit(edges[0], edges[1], edges[2]);
    else
      emit(edges[0], edges[1], edges[3]), emit(edges[1], edges[2], edges[3]);
    return;
  }
  if (n == 5)
    triangulate_pentagon(edges, chords, pos, emit);
  else
    triangulate_polygon(edges, chords, n, pos, emit);
}

// Keeps the better of best and s (the first of equals), as the dynamic programming does.
inline void keep_better(double& best, int& split, double s, int m) {
  if (s > best) best = s, split = m;
}

// triangulate_polygon for n = 5 written out: the same recurrences, comparisons and ties,
// without the loops and tables.
template <class Pos, class Emit>
void triangulate_pentagon(const std::uint8_t* edges, const std::uint16_t* chords, Pos& pos,
                          Emit& emit) {
  const Vec3 &p0 = pos(edges[0]), &p1 = pos(edges[1]), &p2 = pos(edges[2]), &p3 = pos(edges[3]),
             &p4 = pos(edges[4]);
  const double d01 = (p1 - p0).squaredNorm(), d02 = (p2 - p0).squaredNorm(),
               d03 = (p3 - p0).squaredNorm(), d04 = (p4 - p0).squaredNorm(),
               d12 = (p2 - p1).squaredNorm(), d13 = (p3 - p1).squaredNorm(),
               d14 = (p4 - p1).squaredNorm(), d23 = (p3 - p2).squaredNorm(),
               d24 = (p4 - p2).squaredNorm(), d34 = (p4 - p3).squaredNorm();
  const bool ok02 = (chords[0] >> 2) & 1, ok03 = (chords[0] >> 3) & 1, ok13 = (chords[1] >> 3) & 1,
             ok14 = (chords[1] >> 4) & 1, ok24 = (chords[2] >> 4) & 1;
  // Sub-polygons of three points (sides only).
  const double q012 = triangle_quality(d01, d02, d12), q123 = triangle_quality(d12, d13, d23),
               q234 = triangle_quality(d23, d24, d34);
  // Of four points: 0..3 and 1..4.
  double best03 = -2, best14 = -2;
  int split03 = -1, split14 = -1;
  keep_better(best03, split03, std::min(ok13 ? triangle_quality(d01, d03, d13) : -1, q123), 1);
  keep_better(best03, split03, std::min(ok02 ? triangle_quality(d02, d03, d23) : -1, q012), 2);
  keep_better(best14, split14, std::min(ok24 ? triangle_quality(d12, d14, d24) : -1, q234), 2);
  keep_better(best14, split14, std::min(ok13 ? triangle_quality(d13, d14, d34) : -1, q123), 3);
  // The whole cycle.
  double best = -2;
  int split = -1;
  keep_better(best, split, std::min(ok14 ? triangle_quality(d01, d04, d14) : -1, best14), 1);
  keep_better(best, split,
              std::min(std::min(ok02 && ok24 ? triangle_quality(d02, d04, d24) : -1, q012), q234),
              2);
  keep_better(best, split, std::min(ok03 ? triangle_quality(d03, d04, d34) : -1, best03), 3);
  // The triangles in the order of triangulate_polygon's stack.
  const int e0 = edges[0], e1 = edges[1], e2 = edges[2], e3 = edges[3], e4 = edges[4];
  if (split == 1) {
    emit(e0, e1, e4);
    if (split14 == 2)
      emit(e1, e2, e4), emit(e2, e3, e4);
    else
      emit(e1, e3, e4), emit(e1, e2, e3);
  } else if (split == 2) {
    emit(e0, e2, e4), emit(e2, e3, e4), emit(e0, e1, e2);
  } else {
    emit(e0, e3, e4);
    if (split03 == 1)
      emit(e0, e1, e3), emit(e1, e2, e3);
    else
      emit(e0, e2, e3), emit(e0, e1, e2);
  }
}

// Dynamic programming over the sub-polygons a..b of a cycle of n points: best[a][b] is the
// best worst quality of a triangulation of points a..b, split[a][b] the apex of its triangle
// on chord a–b. Ties go to the first apex.
template <class Pos, class Emit>
void triangulate_polygon(const std::uint8_t* edges, const std::uint16_t* chords, int n, Pos& pos,
                         Emit& emit) {
  Vec3 p[12];
  for (int a = 0; a < n; ++a) p[a] = pos(edges[a]);
  // Squared distances computed once: every triangle's quality comes from its three sides.
  double d2[12][12];
  for (int a = 0; a < n; ++a)
    for (int b = a + 1; b < n; ++b) d2[a][b] = (p[b] - p[a]).squaredNorm();
  double best[12][12];
  int split[12][12];
  for (int len = 2; len < n; ++len)
    for (int a = 0; a + len < n; ++a) {
      const int b = a + len;
      best[a][b] = -2;
      split[a][b] = -1;
      for (int m = a + 1; m < b; ++m) {
        const bool ok = (chords[a] >> m) & (chords[m] >> b) & 1;
        double s = ok ? triangle_quality(d2[a][m], d2[a][b], d2[m][b]) : -1;
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

// All cycles of a cell (see triangulate_cycle).
template <class Pos, class Emit>
void triangulate_cell(const CellPolygons& polys, Pos&& pos, Emit&& emit) {
  int start = 0;
  for (int c = 0; c < polys.cycle_count; ++c) {
    const int n = polys.cycle_length[c];
    triangulate_cycle(&polys.edges[start], &polys.chords[start], n, pos, emit);
    start += n;
  }
}

}  // namespace zeroset::detail
