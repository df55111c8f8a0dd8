#pragma once
// The single-precision tests of the floaters' neighbour search: which points of a block of cells
// may lie within reach of a cell's floaters, and of one floater. Most of a block's points do not,
// and these tests are the bulk of the work on them, so they run eight points at a time with AVX2
// where the processor has it, four with SSE2 otherwise, and one at a time elsewhere; every
// variant keeps exactly the same points. Private to the floaters module.
#include <cstddef>
#include <cstdint>
#include <span>

#include "spatial_hash_detail.h"

namespace zeroset::detail {

/// The arrays the filters read must have this many readable entries after each range, and
/// their output this many spare entries after the last index they keep.
inline constexpr std::size_t kFilterPad = 8;

/// The implementations of the filters (kAvx2 needs a processor with AVX2 and FMA).
enum class FilterPath { kScalar, kSse2, kAvx2 };
/// Whether this build and processor can run `path` (the processor is asked once).
bool filter_path_available(FilterPath path);
/// The fastest available path.
FilterPath best_filter_path();

/// Appends to `out`, in order, every index t of the slot `ranges` whose squared distance to
/// (px, py, pz), computed in single precision as (dx² + dy²) + dz², is below
/// max(p_cut, cut[t]); returns how many. `path` must be available. Pure and thread-safe.
std::size_t filter_near(FilterPath path, std::span<const SpatialHash::Range> ranges, const float* x,
                        const float* y, const float* z, const float* cut, float px, float py,
                        float pz, float p_cut, std::uint32_t* out);

/// The same test against the box [lo, hi] (three coordinates each), the bounding box of a cell's
/// floaters, with threshold max(reach, cut[t]): the distance to the box is never more than to a
/// point in it, also after rounding (each operation is monotone), so with `reach` the largest
/// of their thresholds this keeps every index filter_near() keeps for any of them.
std::size_t filter_box(FilterPath path, std::span<const SpatialHash::Range> ranges, const float* x,
                       const float* y, const float* z, const float* cut, const float* lo,
                       const float* hi, float reach, std::uint32_t* out);

/// Doubles in a neighbour record: records are 64-byte aligned groups of this many.
inline constexpr std::size_t kRecordFields = 8;

}  // namespace zeroset::detail
