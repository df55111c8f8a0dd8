#pragma once
// Screen tiles holding the primitives whose projected bounding boxes meet them: the disk and
// mesh renderers and the singular-set overlay visit, per tile, only the pixels of each
// primitive's box. Private to the render module.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "zeroset/render/view.h"

namespace zeroset::detail {

constexpr int kTile = 16;  // screen tiles: the bins, and the tiles rendered

/// Primitive indices per screen tile, and each primitive's pixel bounding box.
struct Bins {
  struct Rect {
    int x0 = 0, y0 = 0, x1 = -1, y1 = -1;  // inclusive pixel range
  };
  int tiles_x = 0, tiles_y = 0;
  std::vector<std::vector<std::uint32_t>> bins;
  std::vector<Rect> rects;

  Bins(int width, int height, size_t primitives)
      : tiles_x((width + kTile - 1) / kTile),
        tiles_y((height + kTile - 1) / kTile),
        bins(static_cast<size_t>(tiles_x) * tiles_y),
        rects(primitives) {}

  /// Adds primitive `id` covering the projections of `points` (all of the image when one of
  /// them is behind the eye; nothing when all are).
  void add(std::uint32_t id, const Vec3* points, int n, const View& view) {
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    int behind = 0;
    for (int i = 0; i < n; ++i) {
      double x, y, depth;
      if (!view.project(points[i], x, y, depth)) {
        ++behind;
        continue;
      }
      x0 = std::min(x0, x);
      x1 = std::max(x1, x);
      y0 = std::min(y0, y);
      y1 = std::max(y1, y);
    }
    if (behind == n) return;
    if (behind > 0) {
      x0 = y0 = 0;
      x1 = view.width;
      y1 = view.height;
    }
    if (!(x1 >= 0 && y1 >= 0 && x0 <= view.width && y0 <= view.height)) return;
    // Pixels whose area meets [x0, x1] × [y0, y1] (every sample of a pixel lies inside it).
    Rect r;
    r.x0 = std::clamp(static_cast<int>(std::floor(x0)), 0, view.width - 1);
    r.x1 = std::clamp(static_cast<int>(std::floor(x1)), 0, view.width - 1);
    r.y0 = std::clamp(static_cast<int>(std::floor(y0)), 0, view.height - 1);
    r.y1 = std::clamp(static_cast<int>(std::floor(y1)), 0, view.height - 1);
    rects[id] = r;
    for (int ty = r.y0 / kTile; ty <= r.y1 / kTile; ++ty)
      for (int tx = r.x0 / kTile; tx <= r.x1 / kTile; ++tx)
        bins[static_cast<size_t>(ty) * tiles_x + tx].push_back(id);
  }
  const std::vector<std::uint32_t>& at(int x0, int y0) const {
    return bins[static_cast<size_t>(y0 / kTile) * tiles_x + x0 / kTile];
  }
};

}  // namespace zeroset::detail
