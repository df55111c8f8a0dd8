#pragma once
/// Export of a ray-traced view to POV-Ray 3.7 (docs/architecture.md, "Modules"): the same camera,
/// lights, colours and clip, with the surface as a `polynomial { N, xyz(i,j,k):c, ... sturm }`
/// object, so users can render it in the tool they know:
///   povray +W800 +H800 +Iscene.pov +Oscene.png
#include <string>

#include "zeroset/render/render.h"

namespace zeroset {

/// The scene text. Front and back materials become `texture` and `interior_texture` (POV-Ray's
/// inside of a polynomial is where it is negative, our back side). Lights are shadowless and
/// parallel, as in render_surface. The image aspect ratio comes from options.width/height.
/// Throws BadInput when F is not a polynomial (or above degree 35, POV-Ray's limit), a
/// parameter has no value, or the clip is unbounded.
std::string pov_scene(const Surface& surface, const RenderOptions& options);

/// Writes pov_scene(...) to `path` atomically. Throws BadInput / IoError.
void write_pov_scene(const Surface& surface, const RenderOptions& options,
                     const std::string& path);

}  // namespace zeroset
