#pragma once
// Image comparisons for the render tests: which pixels show the surface, and how two such
// masks overlap.
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "zeroset/io/image.h"

namespace zeroset::test {

/// True for every pixel that differs from the (linear) background colour by more than a few
/// levels in some channel.
inline std::vector<bool> surface_mask(const Image& img, const Color& background) {
  Image bg(1, 1);
  bg.set_linear(0, 0, background);
  std::vector<bool> mask(static_cast<size_t>(img.width) * img.height);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const std::uint8_t* p = img.pixel(x, y);
      bool differs = false;
      for (int k = 0; k < 3; ++k) differs |= std::abs(int(p[k]) - int(bg.rgb[k])) > 8;
      mask[static_cast<size_t>(y) * img.width + x] = differs;
    }
  return mask;
}

inline double intersection_over_union(const std::vector<bool>& a, const std::vector<bool>& b) {
  size_t inter = 0, uni = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) {
    inter += a[i] && b[i];
    uni += a[i] || b[i];
  }
  return uni == 0 ? 1.0 : static_cast<double>(inter) / static_cast<double>(uni);
}

/// Background pixels whose four neighbours all show the surface: pin holes.
inline int count_holes(const std::vector<bool>& mask, int w, int h) {
  int holes = 0;
  auto at = [&](int x, int y) { return bool(mask[static_cast<size_t>(y) * w + x]); };
  for (int y = 1; y + 1 < h; ++y)
    for (int x = 1; x + 1 < w; ++x)
      holes += !at(x, y) && at(x - 1, y) && at(x + 1, y) && at(x, y - 1) && at(x, y + 1);
  return holes;
}

}  // namespace zeroset::test
