#pragma once
/// Export of a ray-traced view to POV-Ray 3.7 (docs/architecture.md, "Modules"): the same camera,
/// lights, colours and clip, with the surface as a `polynomial { N, xyz(i,j,k):c, ... sturm }`
/// object, so users can render it in the tool they know:
///   povray +W800 +H800 +Iscene.pov +Oscene.png
#include <string>

#include "zeroset/render/render.h"
#include "zeroset/surface/keyframes.h"

namespace zeroset {

/// The scene text. Front and back materials become `texture` and `interior_texture` (POV-Ray's
/// inside of a polynomial is where it is negative, our back side). Lights are shadowless and
/// parallel, as in render_surface. The image aspect ratio comes from options.width/height.
/// Throws BadInput when F is not a polynomial (or above degree 35, POV-Ray's limit), a
/// parameter has no value, or the clip is unbounded.
std::string pov_scene(const Surface& surface, const RenderOptions& options);

/// Writes pov_scene(...) to `path` atomically. Throws BadInput / IoError.
void write_pov_scene(const Surface& surface, const RenderOptions& options, const std::string& path);

/// A keyframed animation for POV-Ray: the scene text, driven by `clock` (0 at the first frame,
/// 1 at the last: the animation time of Keyframes). Each track becomes a piecewise function of
/// clock with the same eases (#if/#elseif over clock); the camera (eye, sky, angle) and the
/// lights that follow it are computed from the tracks' values as Camera::frame does. The
/// polynomial's coefficients are polynomials in the animated parameters, found by fitting
/// expansions of F over the parameters' range and checked to rounding; a surface whose
/// coefficients are not polynomials of degree ≤ 8 in them (a square root of a parameter, say)
/// is refused with BadInput, as are the still export's refusals.
std::string pov_animation_scene(const Surface& surface, const RenderOptions& options,
                                const Keyframes& keys);

/// The frames an animation file renders: `frames` in all (numbered from 0, clock f/(frames−1))
/// of which first..last.
struct PovFrames {
  int frames = 1;
  int first = 0, last = 0;
};

/// The POV-Ray .ini that renders `pov_file` (a name relative to POV-Ray's working directory) as
/// those frames, at the options' size, into OUTPUT_PREFIX<frame number>.png.
std::string pov_animation_ini(const std::string& pov_file, const std::string& output_prefix,
                              const RenderOptions& options, const PovFrames& frames);

/// Writes pov_animation_scene(...) to `pov_path` and its .ini beside it (the same name ending in
/// .ini), both atomically; the frames are named after the .pov file: NAME_<frame>.png. Throws
/// BadInput / IoError.
void write_pov_animation(const Surface& surface, const RenderOptions& options,
                         const Keyframes& keys, const PovFrames& frames,
                         const std::string& pov_path);

}  // namespace zeroset
