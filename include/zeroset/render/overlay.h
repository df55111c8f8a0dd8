#pragma once
/// The singular set drawn over a picture: its curves as thin tubes and its special points as
/// small spheres, coloured by kind, depth-tested against the surface (or the mesh, or the
/// disks) and shaded with the picture's lights. Curves with no sheet through them (Whitney's
/// handle, the Roman surface's whiskers) show too, although a ray tracer of F = 0 cannot see
/// them. Set RenderOptions::singular_overlay to draw it.
#include "zeroset/surface/singular_set.h"
#include "zeroset/types.h"

namespace zeroset {

/// What to draw and how. The default colours (linear RGB) stand apart from each other, from
/// the default orange front and dark blue back and from a white background:
///   curves   crossing: green, isolated: magenta, degenerate: cyan;
///   points   node: near-black, pinch: red, triple: yellow, clip end: grey, degenerate: cyan.
struct SingularOverlay {
  SingularSet set;          ///< usually find_singular_set(surface)
  double tube_radius = 0;   ///< radius of the curves' tubes; 0: 0.006 × the scene radius
  double point_radius = 0;  ///< radius of the points' spheres; 0: 0.015 × the scene radius

  Color crossing = Color(0.03, 0.55, 0.06);
  Color isolated = Color(0.75, 0.03, 0.62);
  Color degenerate = Color(0.0, 0.55, 0.85);

  Color node = Color(0.03, 0.03, 0.03);
  Color pinch = Color(0.85, 0.02, 0.02);
  Color triple = Color(0.95, 0.8, 0.05);
  Color clip_end = Color(0.35, 0.35, 0.35);
  Color degenerate_point = Color(0.0, 0.55, 0.85);

  /// The Phong terms the parts are lit with (their diffuse colour is the kind's). More ambient
  /// light than the surface gets keeps a thin tube's colour recognisable on its shadowed side.
  double ambient = 0.3;
  double specular = 0.3;
  double shininess = 30;

  /// The colour of a curve, or of a point, of this kind.
  const Color& color(CurveKind kind) const;
  const Color& color(SingularPointKind kind) const;
  /// The tubes' radius: tube_radius, or 0.006 × `scene_radius` when that is 0. Throws
  /// InvalidArgument for a negative or non-finite radius.
  double tube_radius_for(double scene_radius) const;
  /// The spheres' radius: point_radius, or 0.015 × `scene_radius` when that is 0. Throws
  /// InvalidArgument for a negative or non-finite radius.
  double point_radius_for(double scene_radius) const;
};

}  // namespace zeroset
