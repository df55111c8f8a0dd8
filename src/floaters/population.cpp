// Fission and death: the fates judge_fate() chose, carried out serially.
#include "floater_state_detail.h"

#include <numbers>

namespace zeroset::detail {

// Removes the floaters at the increasing indices `holes`, filling each with the last floater
// that stays: O(removed) instead of moving everything behind the first hole.
void remove_floaters(FloaterState& sys, std::span<const std::uint32_t> holes) {
  std::size_t last = floater_count(sys), front = 0, back = holes.size();
  while (front < back) {
    if (holes[back - 1] == last - 1) {  // the last floater goes too
      --back;
      --last;
      continue;
    }
    move_floater(sys, last - 1, holes[front]);
    ++front;
    --last;
  }
  resize_state(sys, last);
}

std::size_t remove_undefined(FloaterState& sys) {
  const std::size_t n = floater_count(sys);
  const double tolerance = 1e-9 * sys.surface.scene_radius();
  sys.gone.clear();
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isfinite(sys.value[i]) || !std::isfinite(sys.gnorm[i]) || !sys.pos[i].allFinite() ||
        !std::isfinite(sys.sigma[i]) || !sys.surface.clip.contains(sys.pos[i], tolerance))
      sys.gone.push_back(static_cast<std::uint32_t>(i));
  if (sys.gone.empty()) return 0;
  const std::size_t removed = sys.gone.size();
  remove_floaters(sys, sys.gone);
  sys.gone.clear();
  evaluate_all(sys);
  return removed;
}

namespace {

// Fission: both halves get σ/√2; the child starts at a random tangential offset of a quarter
// to half the old radius (FloaterOptions::fission_offset; without it where its parent is).
// Without clip projection a child that would start outside the clip is not made (returns
// false).
bool split_floater(FloaterState& sys, std::size_t i) {
  Rng rng(sys.opt.seed, sys.id[i], sys.step_count, Stream::kFission);
  const double s = sys.sigma[i];
  Vec3 t1, t2;
  tangent_basis(sys.unit[i], t1, t2);
  const double theta = rng.uniform(0, 2 * std::numbers::pi);
  const double r = rng.uniform(0.25, 0.5) * s;
  // Without the offset (Witkin–Heckbert's plain split) the twins coincide; the pair kernel
  // separates coincident floaters along a direction from their ids.
  Vec3 p = sys.pos[i];
  if (sys.opt.fission_offset) p += r * (std::cos(theta) * t1 + std::sin(theta) * t2);
  if (sys.opt.clip_projection)
    p = sys.surface.clip.project(p);
  else if (!sys.surface.clip.contains(p))
    return false;
  sys.sigma[i] = s / std::numbers::sqrt2;
  push_floater(sys, p, s / std::numbers::sqrt2, sys.mu[i]);
  sys.smax.back() = sys.smax[i];
  return true;
}

}  // namespace

// docs/algorithms.md A.7 with the fates judge_fate() chose, serial so the outcome is the same on
// any number of threads: at most one event per floater, and no fission beyond the cap.
FateCounts decide_fates(FloaterState& sys) {
  FateCounts result;
  const std::size_t n = floater_count(sys);
  std::size_t live = n;
  sys.gone.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (sys.fate[i] == 0) continue;
    if (sys.fate[i] & kStray) {
      sys.gone.push_back(static_cast<std::uint32_t>(i));
      --live;
      ++result.removed;
    } else if ((sys.fate[i] & kFission) && live < sys.opt.max_count && split_floater(sys, i)) {
      ++live;
      ++result.births;
    } else if (sys.fate[i] & kDeath) {
      sys.gone.push_back(static_cast<std::uint32_t>(i));
      --live;
      ++result.deaths;
    }
  }
  remove_floaters(sys, sys.gone);
  return result;
}

}  // namespace zeroset::detail
