// SurfaceRayCaster: casting one ray of a row, through its packet when it has one (see
// raycast_detail.h for the parts).
#include "zeroset/render/raycast.h"

#include <cmath>
#include <limits>
#include <optional>
#include <span>

#include "raycast_detail.h"

namespace zeroset {
namespace detail {
namespace {

/// The lane of the packet that holds the ray at s, or −1. Rays come in order, so the lane
/// after the last one found is tried first.
int packet_lane(RayCaster& rc, double s) {
  if (rc.packet_next < rc.packet_size && rc.packet_s[static_cast<size_t>(rc.packet_next)] == s)
    return rc.packet_next;
  for (int i = 0; i < rc.packet_size; ++i)
    if (rc.packet_s[static_cast<size_t>(i)] == s) {
      rc.packet_next = i;
      return i;
    }
  return -1;
}

/// exact_hit for a ray of the packet (lane i), after the clip said it is inside.
double packet_hit(RayCaster& rc, int i, const RootGuess& guess, double& band) {
  const size_t lane = static_cast<size_t>(i);
  band = rc.packet_band[lane];
  // A vanishing leading coefficient lowers the degree: the general entry trims it.
  if (!((rc.packet_full_bits >> i) & 1))
    return rc.finder.find_first_root(
        std::span<const double>(lane_coeffs(rc, i), static_cast<size_t>(rc.degree + 1)),
        rc.packet_t0[lane], rc.packet_t1[lane], band, guess);
  return rc.finder.find_first_root_on_unit(
      std::span<const double>(rc.packet_g[lane], static_cast<size_t>(rc.degree + 1)),
      rc.packet_t0[lane], rc.packet_t1[lane], band, guess);
}

/// The first hit of the row's ray at s (NaN: none), and the side of the surface the ray
/// starts on (+1, −1, 0 when F vanishes there).
double cast(RayCaster& rc, double s, const RootGuess& guess, int& side) {
  constexpr double kNone = std::numeric_limits<double>::quiet_NaN();
  rc.cast_lane = rc.packet_ready ? packet_lane(rc, s) : -1;
  if (const int lane = rc.cast_lane; lane >= 0) {
    if (!rc.packet_open[static_cast<size_t>(lane)]) return kNone;
    double band = 0;
    double t = packet_hit(rc, lane, guess, band);
    double v = rc.finder.start_value();
    const size_t i = static_cast<size_t>(lane);
    if (!std::isnan(t) &&
        !hit_is_certain(rc, lane_coeffs(rc, lane), t, band, direction(rc, s).norm()))
      t = accurate_hit(rc, s, rc.packet_t0[i], rc.packet_t1[i], guess, band, v);
    side = std::abs(v) <= band ? 0 : (v > 0 ? 1 : -1);
    return t;
  }
  double t0 = 0, t1 = 0;
  if (!clip(rc, s, t0, t1)) return kNone;
  if (rc.exact) {
    double band = 0;
    double t = exact_hit(rc, s, t0, t1, guess, band);
    double v = rc.finder.start_value();
    if (!std::isnan(t) && !hit_is_certain(rc, rc.coeffs.data(), t, band, direction(rc, s).norm()))
      t = accurate_hit(rc, s, t0, t1, guess, band, v);
    // F keeps its sign on [t0, hit) since the hit is the first root.
    side = std::abs(v) <= band ? 0 : (v > 0 ? 1 : -1);
    return t;
  }
  const Vec3 origin = ray_origin(rc, s), dir = direction(rc, s);
  const std::optional<double> t = interval_hit(rc, origin, dir, t0, t1);
  if (!t) return kNone;
  const double v = value_on_ray(rc, origin, dir, t0);
  side = v > 0 ? 1 : (v < 0 ? -1 : 0);
  return *t;
}

/// first_hit_in_row: cast, and keep the hit for packet_hits when s is in the packet.
double first_hit_in_row(RayCaster& rc, double s, const RootGuess& guess) {
  int side = 0;
  const double t = cast(rc, s, guess, side);
  const int lane = rc.packet_ready ? rc.cast_lane : packet_lane(rc, s);
  if (lane < 0) return t;
  rc.packet_next = lane + 1;
  if (std::isnan(t)) return t;
  const size_t i = static_cast<size_t>(lane);
  rc.packet_hit_bits |= 1 << lane;
  if (rc.packet_ready) {
    rc.packet_t[i] = t;
    rc.packet_side[i] = side;
  } else {
    // The ray's polynomial is not kept past the next ray: complete the hit now.
    complete(rc, s, t, side, rc.packet_done[i]);
    rc.packet_done_bits |= 1 << lane;
  }
  return t;
}

bool intersect_in_row(RayCaster& rc, double s, SurfaceHit& hit, const RootGuess& guess) {
  int side = 0;
  const double t = cast(rc, s, guess, side);
  if (std::isnan(t)) return false;
  if (rc.cast_lane >= 0) rc.ray_coeffs = lane_coeffs(rc, rc.cast_lane);
  complete(rc, s, t, side, hit);
  return true;
}

}  // namespace
}  // namespace detail

struct SurfaceRayCaster::Impl : detail::RayCaster {
  using RayCaster::RayCaster;
};

SurfaceRayCaster::SurfaceRayCaster(const Surface& surface, const Vec3& eye,
                                   const RaycastOptions& options)
    : impl_(std::make_unique<Impl>(surface, eye, options)) {}
SurfaceRayCaster::~SurfaceRayCaster() = default;
SurfaceRayCaster::SurfaceRayCaster(SurfaceRayCaster&&) noexcept = default;
SurfaceRayCaster& SurfaceRayCaster::operator=(SurfaceRayCaster&&) noexcept = default;

bool SurfaceRayCaster::is_exact() const { return impl_->exact; }
std::optional<double> SurfaceRayCaster::first_hit(const Vec3& dir) {
  detail::begin_row(*impl_, dir, Vec3::Zero());
  int side = 0;
  const double t = detail::cast(*impl_, 0.0, {}, side);
  return std::isnan(t) ? std::nullopt : std::optional<double>(t);
}
bool SurfaceRayCaster::intersect(const Vec3& dir, SurfaceHit& hit) {
  detail::begin_row(*impl_, dir, Vec3::Zero());
  return detail::intersect_in_row(*impl_, 0.0, hit, {});
}
void SurfaceRayCaster::begin_row(const Vec3& base, const Vec3& step) {
  detail::begin_row(*impl_, base, step);
}
void SurfaceRayCaster::begin_parallel_row(const Vec3& origin, const Vec3& origin_step,
                                          const Vec3& dir) {
  detail::begin_parallel_row(*impl_, origin, origin_step, dir);
}
void SurfaceRayCaster::row_extent(double& s_min, double& s_max) const {
  s_min = impl_->s_min;
  s_max = impl_->s_max;
}
int SurfaceRayCaster::prepare_in_row(std::span<const double> s) {
  return detail::prepare(*impl_, s);
}
bool SurfaceRayCaster::first_hit_in_row(double s, const RootGuess& guess, double& t) {
  t = detail::first_hit_in_row(*impl_, s, guess);
  return !std::isnan(t);
}
int SurfaceRayCaster::packet_hits(SurfaceHit (&hits)[4]) {
  return detail::packet_hits(*impl_, hits);
}
bool SurfaceRayCaster::intersect_in_row(double s, SurfaceHit& hit, const RootGuess& guess) {
  return detail::intersect_in_row(*impl_, s, hit, guess);
}
const RootStats& SurfaceRayCaster::root_stats() const { return impl_->finder.stats(); }
long long SurfaceRayCaster::abandoned_rays() const { return impl_->abandoned_rays; }
long long SurfaceRayCaster::accurate_rays() const { return impl_->accurate_rays; }

}  // namespace zeroset
