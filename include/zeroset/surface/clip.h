#pragma once
/// Clip volumes (docs/algorithms.md A.6; paper §3.2): an intersection of spheres and half spaces.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "zeroset/expr/field.h"
#include "zeroset/types.h"

namespace zeroset {

/// The largest magnitude of a clip coordinate: a sphere's radius and centre coordinates, a box's
/// corner coordinates, a plane's distance from the origin. Beyond the surfaces of interest (the
/// Kummer family's clip reaches 1.33e6 at mu = 1.28e6, docs/singular.md), and small enough
/// that polynomials of moderate degree stay finite anywhere in the volume.
inline constexpr double kMaxClipCoordinate = 1e7;
/// The smallest size of a clip part relative to where it lies: a sphere's radius, a box's
/// sides and the clip's bounding box sides are at least kMinClipRelativeSize·max(1, |x|) for
/// its largest coordinate |x|. Points in a smaller volume far from the origin differ only in
/// their last bits (sphere:1e-300@1,0,0 holds one double), and the absolute tolerances of the
/// algorithms (1e-9 and below) would swallow a tiny volume at the origin.
inline constexpr double kMinClipRelativeSize = 1e-6;

/// The ball |x - center| ≤ radius.
struct SphereClip {
  Vec3 center = Vec3::Zero();
  double radius = 1;
};

/// The half space normal·x ≤ offset; `normal` has unit length.
struct HalfSpaceClip {
  Vec3 normal = Vec3::UnitZ();
  double offset = 0;
};

/// Most parts (spheres and half spaces) of one clip. Every stage tests the clip at every point
/// it looks at, so the cost of a test grows with the parts; a handful is the use, and this
/// bound keeps a clip of absurd length (a million specs in a scene file) from stalling work.
inline constexpr std::size_t kMaxClipParts = 256;

/// A clip spec whose numbers are expressions of the surface's parameters, such as
/// "sphere:3*sqrt(mu)" (docs/scenes.md): its text, its numbers compiled, and the parts it sets.
struct ClipFormula {
  std::string spec;            ///< as given; to_specs() writes it back
  std::vector<Field> numbers;  ///< every number of the spec in order (a sphere's centre last)
  std::size_t first = 0;       ///< its first part: an index into spheres (a sphere spec) or
                               ///< planes (a plane spec: one, a box: six)
  bool sphere = false;         ///< the spec is a sphere
};

/// An intersection of spheres and half spaces; empty lists mean "no clip" (all of space).
/// The signed clip function G is negative inside, zero on the boundary and positive outside:
/// G(x) = max over parts of (|x - c| - r) and (n·x - d).
struct Clip {
  std::vector<SphereClip> spheres;
  std::vector<HalfSpaceClip> planes;
  /// The parametric specs; their parts hold the values of the last update().
  std::vector<ClipFormula> formulas;

  static Clip sphere(double radius, const Vec3& center = Vec3::Zero());
  static Clip box(const Box3& box);  ///< six half spaces

  /// Parses one clip spec and intersects it into this clip. Specs:
  ///   sphere:R  sphere:R@cx,cy,cz  box:H (cube [-H,H]^3)  box:x0,y0,z0,x1,y1,z1
  ///   plane:nx,ny,nz,d (keeps n·x ≤ d; n is normalised)
  /// A number may be an expression of the surface's parameters (not of x, y, z), such as
  /// sphere:3*sqrt(mu); its parts get their values from update(), which must follow.
  /// Throws InvalidArgument naming the spec and what is wrong, including numbers beyond
  /// kMaxClipCoordinate, parts smaller than kMinClipRelativeSize allows, and a clip of more
  /// than kMaxClipParts parts.
  void add(std::string_view spec);
  /// Checks the whole volume once its parts are added: its bounding box (as far as it is
  /// bounded) must not be empty or thinner than kMinClipRelativeSize allows. Throws
  /// InvalidArgument.
  void check_extent() const;

  /// Evaluates the parametric specs' numbers at the field's parameter values and sets their
  /// parts, checked as add() checks numbers, then checks the extent. Throws InvalidArgument
  /// (BadInput) for a name the field lacks, a parameter without a value, a value that is not
  /// finite and a part beyond the clip limits. Nothing to do for a constant clip. Cost: a few
  /// evaluations of tiny expressions; call it whenever the parameters change.
  void update(const Field& field);
  bool is_parametric() const { return !formulas.empty(); }

  bool is_empty_spec() const { return spheres.empty() && planes.empty(); }
  /// True when the clip volume has a finite bounding box (a sphere, or axis-aligned planes
  /// closing a box; oblique planes alone are not recognised as bounding).
  bool is_bounded() const;
  bool contains(const Vec3& p, double tolerance = 0) const;
  /// G(p) (see above).
  double value(const Vec3& p) const;
  /// G(p) and the gradient of the active part.
  double value_gradient(const Vec3& p, Vec3& gradient) const;
  /// Paper §3.2: for each part the point violates, project it back onto that part's boundary:
  /// orthogonally onto a plane, radially towards a sphere's centre. Returns p when inside.
  Vec3 project(const Vec3& p) const;
  /// A bounding box of the clip volume. Throws BadInput when the clip is unbounded.
  Box3 bounds() const;
  /// Parameter interval [t0, t1] of the ray o + t·d inside the clip (t ≥ t_min);
  /// false when the ray misses it.
  bool ray_interval(const Vec3& o, const Vec3& d, double t_min, double& t0, double& t1) const;
  /// The specs that rebuild this clip ("sphere:3", "plane:0,0,1,0.5", ...); a parametric
  /// spec as it was given, or with `values` its parts at the last update().
  std::vector<std::string> to_specs(bool values = false) const;
};

}  // namespace zeroset
