#pragma once
/// A surface: compiled field + parameter values + clip + how to look at it (docs/architecture.md,
/// "From text to output").
#include <functional>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "zeroset/expr/field.h"
#include "zeroset/surface/clip.h"
#include "zeroset/types.h"

namespace zeroset {

/// A parameter's range (for sliders and animation). Its value lives in the surface's field
/// (Field::parameter_values), nowhere else.
struct ParamSpec {
  std::string name;
  double min = 0;
  double max = 1;
};

/// Where a camera is and which way it looks: the eye, the unit direction towards the target,
/// and the unit image directions right (x) and up (y). right, up, -forward is a right-handed
/// orthonormal frame.
struct CameraFrame {
  Vec3 eye;
  Vec3 forward;
  Vec3 right;
  Vec3 up;
};

/// How a camera maps the world to its picture: a pinhole (rays from the eye, sizes shrink with
/// depth) or parallel rays along the view direction (sizes independent of depth).
enum class Projection { perspective, orthographic };

/// An orbit camera: looks at `target` from `distance` along the direction given by azimuth
/// (around +z, from +x) and elevation (above the xy plane). z is up, unless `roll_deg` turns
/// the camera about its view direction. An orthographic camera shows a window `ortho_height`
/// world units high; its rays start on the plane through the eye (placed outside the clip
/// volume, see eye()) and all run along the view direction.
struct Camera {
  double azimuth_deg = 30;
  double elevation_deg = 20;
  double distance = 0;  ///< 0: chosen from the clip's size so the whole volume is in view
  double fov_deg = 30;  ///< vertical field of view
  Vec3 target = Vec3::Zero();
  /// Turns the camera counterclockwise about its view direction (as its user sees it), so the
  /// picture turns clockwise; 0 keeps z up. With it every orientation can be given, such as a
  /// SURFER file's rotation (docs/scenes.md).
  double roll_deg = 0;
  Projection projection = Projection::perspective;
  /// Orthographic only: the height of the visible window in world units; 0: chosen from the
  /// clip's size so the whole volume is in view (view_height).
  double ortho_height = 0;

  bool is_orthographic() const { return projection == Projection::orthographic; }
  /// The eye position; `scene_radius` is used when distance == 0. An orthographic camera's
  /// eye (where its rays start) is at least 2.5 scene radii from the target, so that the
  /// rays start outside the clip volume whatever the distance.
  Vec3 eye(double scene_radius) const;
  /// Orthographic: the visible window's height in world units, ortho_height or, when it is
  /// 0, 2.16 · scene_radius (the clip's ball with the perspective fit's margin).
  double view_height(double scene_radius) const;
  /// The eye and the view's directions (the one home of the orbit camera's orientation: the
  /// renderers, the viewer and the exports all go through it). Looking straight up or down,
  /// the unrolled image's up is the azimuth's direction. Meaningful only when the eye differs
  /// from the target.
  CameraFrame frame(double scene_radius) const;
  /// Without a distance: this camera aimed at the centre of the points' bounding box, from
  /// the distance at which the ball around it holding them all (radius at least
  /// `min_radius`) fills the field of view. The clip volume can be much larger than what lies
  /// on the surface inside it (the cone fills a third of its clip sphere). With a distance, or
  /// no points, the camera as it is. Orthographic without a height: the height fits that
  /// ball in the same way.
  Camera aimed_at(std::span<const Vec3> points, double min_radius) const;
};

/// Known singular points of a surface for given parameter values (may be empty).
using SingularPointsFn = std::function<std::vector<Vec3>(const Field&)>;

/// Everything that defines what is drawn. A value type: copying is cheap (the field's tape is
/// shared). `name` is the catalog name, or empty for a typed equation.
struct Surface {
  std::string name;
  std::string title;
  Field field;
  Clip clip;
  Camera camera;
  std::vector<ParamSpec> ranges;  ///< one per parameter of `field`, in its order
  SingularPointsFn singular_points_fn;

  /// Makes `ranges` one per parameter of `field`, in its order: a range given for the name
  /// (with min < max, both within ±kMaxParameterMagnitude) is kept, a missing one spans
  /// value ± max(1, |value|) (0 ± 1 for a parameter without a value). Every span max - min is
  /// finite. Cost n log n for n parameters.
  void fit_ranges();

  /// Known singular points for the current parameter values, inside the clip.
  std::vector<Vec3> singular_points() const;
  /// The clip's bounding box; throws BadInput naming the surface when it has no bounded clip.
  Box3 bounds() const;
  /// Radius of a ball around the clip's bounding box centre that holds the clip volume.
  double scene_radius() const;
  /// A short label: the catalog name or the equation.
  std::string label() const;
};

}  // namespace zeroset
