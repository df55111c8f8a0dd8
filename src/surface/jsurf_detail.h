#pragma once
// What SURFER's .jsurf files fix, shared by their reader (jsurf.cpp) and writer
// (jsurf_write.cpp). Private to the surface module.

namespace zeroset::detail {

/// SURFER's colours are what the screen shows; zeroset shades in linear values and encodes its
/// pictures with gamma 2.2 (zeroset/render/settings.h), so a colour goes through this power.
inline constexpr double kJsurfGamma = 2.2;
/// jsurf has eight light slots.
inline constexpr int kJsurfLights = 8;

}  // namespace zeroset::detail
