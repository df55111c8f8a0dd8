#pragma once
// The state of a SurfaceRayCaster and the functions that share it, one file per part: the
// polynomial's terms (raycast_setup.cpp), a row's expansion and clip and the first root of one
// ray (raycast_rows.cpp), packets of four rays (raycast_packets.cpp), the normals of hits
// (raycast_normals.cpp), fields that are not polynomials (raycast_interval.cpp), and casting
// with the public class (raycast.cpp). Private to the render module.
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "double_double_detail.h"
#include "raycast_monomials_detail.h"
#include "zeroset/expr/interval.h"
#include "zeroset/expr/polynomial.h"
#include "zeroset/render/raycast.h"

namespace zeroset::detail {

constexpr int kN = RootFinder::kMaxDegree + 1;
// |∇F| below this fraction of the magnitude of its terms counts as ∇F = 0 (see complete).
constexpr double kRelativeGradientFloor = 1e-6;
// ∇F from the row's expansions is used when it exceeds that floor by this factor and the
// bound on its own rounding error by kRowGradientAccuracy (see complete). That bound is a
// worst case, orders of magnitude above the actual error: the reference scenes shade the
// same as with ∇F from F's own terms.
constexpr double kRowGradientMargin = 1e3;
constexpr double kRowGradientAccuracy = 1e3;

constexpr double square(double x) { return x * x; }
/// |v|², with fused multiply-adds in the order the packets use.
inline double squared_norm(double x, double y, double z) {
  return std::fma(z, z, std::fma(y, y, x * x));
}
/// lo < x < ∞ (false for NaN).
inline bool in_open_range(double x, double lo) {
  return x > lo && x < std::numeric_limits<double>::infinity();
}

/// A term c·x^i y^j z^k of G (F translated to the eye): its monomial's position in
/// RayCaster::row_monomials and its degree.
struct RowTerm {
  int position, degree;
  double c;
};
/// A term of ∇G, with vector coefficient (∂G/∂x, ∂G/∂y, ∂G/∂z).
struct PartialsTerm {
  int position, degree;
  Vec3 c;
};
/// A clip sphere along a row's rays (as Clip::ray_interval, with its terms expanded in s).
struct SphereRow {
  double a0, a1, a2;  // |d|² = a0 + 2 a1 s + a2 s²
  double b0, b1;      // (eye − centre)·d = b0 + b1 s
  double c;           // |eye − centre|² − radius²
};
/// A clip half-space along a row's rays.
struct PlaneRow {
  double n0, n1;  // normal·d = n0 + n1 s
  double g;       // normal·eye − offset
};
/// A term of G in double-double (the accurate path): its monomial's position in
/// RayCaster::row_monomials, its degree, its value and the sum of the magnitudes added into it.
struct AccurateTerm {
  int position, degree;
  DoubleDouble c;
  double magnitude;
};
// A hit stands when its rounding band places it within this fraction of the clip radius
// (band / |f'| along the ray); others go through the accurate path, or are halved there. The
// band is a worst case: against the long-double reference (tests/render/record_rays_test.cpp
// and raycast_test.cpp) the hits it admits lie within 1e-7 of the clip radius, a hundred times
// closer, while a bound of 1e-7 itself would send half of Barth's sextic through the accurate
// path (see docs/rendering.md, "Accuracy").
constexpr double kCertainHit = 1e-5;
// The accurate path halves a piece of the ray at most this many times (see accurate_hit).
constexpr int kAccurateDepth = 12;
/// A piece [a, b] of a ray on the interval path's subdivision stack.
struct Segment {
  double a, b;
};

// The highest degree whose packets run four rays per instruction, and the size of a row's
// triangle of coefficients up to it.
constexpr int kPacketDegree = 6;
constexpr int kPacketRow = (kPacketDegree + 1) * (kPacketDegree + 2) / 2;

/// Everything a SurfaceRayCaster keeps: the surface's terms, set up once, and the current row
/// and packet, rewritten as rays are cast. Owns scratch memory: one per thread.
struct RayCaster {
  Surface surface;
  Vec3 eye;
  RaycastOptions options;
  Evaluator evaluator;
  bool exact = false;
  int degree = 0;
  // Polynomial path. F's own terms and their absolute values (for the rounding band).
  Polynomial polynomial;
  std::vector<Monomial> abs_terms;
  std::vector<int> degree_of;  // [m]: the degree of row_monomials' monomial m
  // ∂F/∂x, ∂F/∂y, ∂F/∂z from F's own terms (well conditioned near the
  // surface, unlike the translated form), dense over the monomials of degree < degree.
  MonomialTable derivative_monomials{0};
  std::vector<GradientTerm> derivative;  // the monomials of the derivatives, in order
  std::vector<double> gradient_bound;    // [k]: Σ |coefficient| over degree k of all three
  std::vector<double> powers;            // scratch: monomials of a hit point
  // With bounds[k] the sum of the coefficients of degree k of |F| translated by |eye|,
  // bounds[k]·max|d_i|^k ≥ |G_k(d)| for every direction d and bounds the rounding error scale
  // of G_k. The rounding band of a ray is rounding_band(bounds, t1·max|d_i|), a polynomial in
  // t1·max|d_i| with these coefficients.
  std::array<double, kN> band_coeffs{};
  RootFinder finder;
  std::array<double, kN> coeffs{};

  // For the rows: every monomial of degree ≤ degree (row_monomials), as a polynomial in s at
  // base + s·step, its deg + 1 coefficients at mono_poly[mono_offset[m]]; G's terms and
  // ∇G = (∂G/∂x, ∂G/∂y, ∂G/∂z) (one polynomial with vector coefficients, degree − 1) by
  // their monomials' positions.
  MonomialTable row_monomials{0};
  std::vector<int> mono_offset;
  std::vector<double> mono_poly;
  std::vector<RowTerm> row_terms;
  std::vector<PartialsTerm> translated_gradient;

  // The current row: directions base + s·step from the eye; or, in a parallel row (an
  // orthographic view), rays eye + s·step + t·base.
  Vec3 base = Vec3::UnitX(), step = Vec3::Zero();
  bool parallel = false;
  // Exact path: G_k(base + s·step) = Σ_j row[k(k+1)/2 + j] s^j. By homogeneity G_k(t·base +
  // s·step) = Σ_j row[k(k+1)/2 + j] s^j t^(k−j), which a parallel row's rays use.
  std::array<double, kN*(kN + 1) / 2> row{};
  // Normals along the row (see row_gradient): the derivative in s of row, ∂G_k/∂s =
  // Σ_j row_ds[k(k−1)/2 + j] s^j (k ≥ 1); the normal of the row's plane, n = base × step; and
  // the homogeneous parts of ∇G·n, (∇G·n)_k(base + s·step) = Σ_j normal_row[k(k+1)/2 + j] s^j.
  std::array<double, kN*(kN + 1) / 2> row_ds{};
  std::array<double, kN*(kN + 1) / 2> normal_row{};
  Vec3 row_normal = Vec3::Zero();
  double row_dot = 0, row_ss = 0, row_inverse_nn = 0;  // base·step, |step|², 1 / |n|²
  bool has_row_normals = false;                        // false for a row of one ray (step = 0)
  // The clip along the row's rays.
  std::vector<SphereRow> sphere_rows;
  std::vector<PlaneRow> plane_rows;
  double s_min = 0, s_max = 0;  // see find_row_extent

  // Accurate path (raycast_accurate.cpp): G in double-double, made on the first ray after
  // set_eye that needs it, and scratch for one ray's monomials as polynomials in t.
  double scene_radius = 1;
  bool accurate_ready = false;
  std::vector<AccurateTerm> accurate_terms;
  std::vector<DoubleDouble> accurate_mono;
  std::vector<double> accurate_abs;
  long long accurate_rays = 0;  // rays that took the accurate path

  // Interval path.
  std::unique_ptr<IntervalEvaluator> intervals;
  std::vector<Segment> segments;  // scratch: the subdivision stack
  long long abandoned_rays = 0;   // rays that ran out of RaycastOptions::interval_budget

  // A packet: four rays of the row (prepare_in_row). With AVX2 their straight-line parts are
  // done four at a time, bit for bit what the scalar code computes for each ray: the set-up
  // (clip, restriction, rounding band, shift to the clipped interval) and the first levels of
  // the isolation (hull_misses4) by prepare4, and the normals of their hits (packet_hits) by
  // complete4. The rest of the isolation stays per ray.
  // packet_g[i]: lane i's g (see shift_to_unit); packet_ck[k][i]: the k-th coefficient of lane
  // i's f; packet_open[i]: lane i's ray meets the clip volume and is not known to miss. The
  // lanes' hits: parameters, sides and whether each ray was cast and hit (packet_hit_bits);
  // hits completed at once (rays not set up here) in packet_done.
  std::array<double, 4> packet_s{};
  std::array<double, 4> packet_t0{}, packet_t1{}, packet_band{};
  std::array<bool, 4> packet_open{};
  int packet_full_bits = 0;   // lanes whose f has a nonzero leading coefficient
  int packet_size = 0;        // 4 after prepare_in_row, else 0
  int packet_next = 0;        // the lane packet_lane tries first
  bool packet_ready = false;  // the lanes are set up by prepare4
  alignas(32) double packet_g[4][kN];
  alignas(32) double packet_ck[kN][4];
  const double* ray_coeffs = coeffs.data();  // the current ray's f (see row_gradient)
  int cast_lane = -1;                        // the packet's lane the last cast took, or -1
  // The row's coefficients that the packets use, each in all four lanes (loaded with the
  // multiply-adds rather than broadcast in each packet): row, row_ds, normal_row, the band's
  // and k·band_coeffs[k], gradient_bound.
  alignas(32) double row4[kPacketRow][4];
  alignas(32) double row_ds4[kPacketRow][4];
  alignas(32) double normal_row4[kPacketRow][4];
  alignas(32) double band4[kPacketDegree + 1][4];
  alignas(32) double k_band4[kPacketDegree + 1][4];
  alignas(32) double gradient_bound4[kPacketDegree][4];
  alignas(32) std::array<double, 4> packet_t{}, packet_side{};
  int packet_hit_bits = 0, packet_done_bits = 0;
  std::array<SurfaceHit, 4> packet_done;

  /// Sets up the terms of the surface's polynomial (or the interval evaluator) for rays from
  /// `eye`. Throws BadInput naming the surface when its clip is unbounded.
  RayCaster(const Surface& s, const Vec3& e, const RaycastOptions& o);
};

// raycast_setup.cpp
/// Moves the eye the rays start from: F's terms translated to it and the rounding band's
/// coefficients (O(terms · degree³)); a translation that overflows sends the caster to the
/// interval path. Start a row afterwards.
void set_eye(RayCaster& rc, const Vec3& e);

// raycast_rows.cpp
/// Starts the row of rays base + s·step: the clip and, for polynomials, G along the row.
void begin_row(RayCaster& rc, const Vec3& row_base, const Vec3& row_step);
/// Starts the row of parallel rays origin + s·origin_step + t·dir (see
/// SurfaceRayCaster::begin_parallel_row).
void begin_parallel_row(RayCaster& rc, const Vec3& origin, const Vec3& origin_step,
                        const Vec3& dir);
/// The parameter interval [t0, t1] of the row's ray at s inside the clip (t ≥ 0); false
/// when it misses. The same stable formulas as Clip::ray_interval.
bool clip(const RayCaster& rc, double s, double& t0, double& t1);
/// The first root of f(t) = G(t·(base + s·step)), or G(s·step + t·base) in a parallel row, on
/// [t0, t1] (NaN: none); `band`
/// receives the rounding band used.
double exact_hit(RayCaster& rc, double s, double t0, double t1, const RootGuess& guess,
                 double& band);

// raycast_accurate.cpp
/// Whether the fast path's hit at t on a ray with polynomial f (about the ray's origin) and
/// rounding band `band` is placed within kCertainHit of the clip radius; dir_norm = |dir|.
bool hit_is_certain(const RayCaster& rc, const double* f, double t, double band, double dir_norm);
/// The first root on [t0, t1] of the row's ray at s, from F restricted to the ray in
/// double-double and written on pieces of [t0, t1] before rounding (NaN: none); `band`
/// receives the rounding band of the piece searched last, `start` F at t0.
double accurate_hit(RayCaster& rc, double s, double t0, double t1, const RootGuess& guess,
                    double& band, double& start);

// raycast_packets.cpp
/// See SurfaceRayCaster::prepare_in_row.
int prepare(RayCaster& rc, std::span<const double> s);
/// The hits of the packet's rays that first_hit_in_row found (bit i: lane i hit).
int packet_hits(RayCaster& rc, SurfaceHit (&hits)[4]);

// raycast_normals.cpp
/// The row's ray at s hits at t (side as from cast; the ray's polynomial at ray_coeffs):
/// its point, normal and side. Fused multiply-adds where complete4 uses them.
void complete(RayCaster& rc, double s, double t, int side, SurfaceHit& hit);

// raycast_interval.cpp
/// The first root of F on the ray origin + t·dir, t ∈ [t0, t1], for fields that are not
/// polynomials: interval subdivision, then a bracketed refinement.
std::optional<double> interval_hit(RayCaster& rc, const Vec3& origin, const Vec3& dir, double t0,
                                   double t1);

/// Where the row's ray at s starts: the eye, or eye + s·step in a parallel row.
inline Vec3 ray_origin(const RayCaster& rc, double s) {
  return rc.parallel ? Vec3(rc.eye + s * rc.step) : rc.eye;
}
/// The direction of the row's ray at s: base + s·step, or base in a parallel row.
inline Vec3 direction(const RayCaster& rc, double s) {
  return rc.parallel ? rc.base : Vec3(rc.base + s * rc.step);
}

inline double value_on_ray(RayCaster& rc, const Vec3& origin, const Vec3& dir, double t) {
  return rc.evaluator.value(origin + t * dir);
}

inline void broadcast(const double* v, int n, double (*out)[4]) {
  for (int i = 0; i < n; ++i) out[i][0] = out[i][1] = out[i][2] = out[i][3] = v[i];
}

/// f of the packet's lane i, gathered into `coeffs`.
inline const double* lane_coeffs(RayCaster& rc, int i) {
  for (int k = 0; k <= rc.degree; ++k)
    rc.coeffs[static_cast<size_t>(k)] = rc.packet_ck[k][static_cast<size_t>(i)];
  return rc.coeffs.data();
}

}  // namespace zeroset::detail
