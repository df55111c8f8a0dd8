#pragma once
/// The view of an orbit camera, a pinhole (perspective) or parallel rays (orthographic): eye
/// point, orthonormal frame, and the map between image positions and rays. Shared by the ray
/// caster, the disk and mesh renderers and the POV-Ray export so that they all show exactly the
/// same picture.
#include <Eigen/Geometry>

#include "zeroset/surface/surface.h"
#include "zeroset/types.h"

namespace zeroset {

struct View {
  Vec3 eye = Vec3(0, 0, 1);
  Vec3 target = Vec3::Zero();
  Vec3 forward = Vec3(0, 0, -1);  ///< unit, from the eye towards the target
  Vec3 right = Vec3(1, 0, 0);     ///< unit, image x direction
  Vec3 up = Vec3(0, 1, 0);        ///< unit, image y direction (z up unless looking along z)
  double tan_half_fov = 0.27;     ///< tan of half the vertical field of view (perspective)
  /// Orthographic: every ray runs along `forward` from its own point of the plane through the
  /// eye, the window being 2·half_height world units high.
  bool orthographic = false;
  double half_height = 1;  ///< orthographic only: half the window's height in world units
  int width = 1;           ///< pixels
  int height = 1;          ///< pixels

  /// The view of `camera` for a scene of radius `scene_radius` (used when camera.distance
  /// is 0) on a width × height image. Throws InvalidArgument for a non-positive size, a field
  /// of view outside (0°, 180°), a non-finite camera or a non-positive orthographic height.
  static View from_camera(const Camera& camera, double scene_radius, int width, int height);

  double aspect() const { return static_cast<double>(width) / height; }
  /// Unit direction of the ray through image position (x, y), in pixels from the top-left
  /// corner (pixel centres at +0.5); `forward` for every ray when orthographic.
  Vec3 direction(double x, double y) const;
  /// Where the ray through image position (x, y) starts: the eye, or when orthographic its
  /// point of the plane through the eye.
  Vec3 origin(double x, double y) const;
  /// The rays through image row y, unnormalized: base + x·step points through (x, y), and
  /// direction(x, y) is its normalization (orthographic: base = forward, step = 0).
  void row(double y, Vec3& base, Vec3& step) const;
  /// The origins of the rays through image row y: origin(x, y) = base + x·step.
  void row_origins(double y, Vec3& base, Vec3& step) const;
  /// Image position and depth (distance along `forward` from the eye's plane) of a world
  /// point; false when the point is not in front of the eye (of its plane, orthographic).
  bool project(const Vec3& p, double& x, double& y, double& depth) const;
  /// World-space size of one pixel at depth 1 (perspective).
  double pixel_angle() const { return 2.0 * tan_half_fov / height; }
  /// World-space size of one pixel at the given depth (orthographic: at every depth).
  double pixel_size(double depth) const {
    return orthographic ? 2.0 * half_height / height : pixel_angle() * depth;
  }
  /// A direction given in camera coordinates (x right, y up, z towards the viewer) in world
  /// coordinates.
  Vec3 camera_to_world(const Vec3& v) const { return v.x() * right + v.y() * up - v.z() * forward; }
};

}  // namespace zeroset
