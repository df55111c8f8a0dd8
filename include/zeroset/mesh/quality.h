#pragma once
/// Mesh quality metrics (docs/algorithms.md F.1), computed the same way for every mesh.
#include <array>
#include <vector>

#include "zeroset/mesh/mesh.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

struct QualityOptions {
  /// Vertices and triangles within this distance of a known singular point are left out of the
  /// residual and normal figures (|F|/|∇F| and ∇F mean nothing there). 0: 2 mean edge lengths.
  double singular_radius = 0;
  int threads = 0;  ///< 0: all cores
};

struct MeshQuality {
  size_t vertices = 0;
  size_t triangles = 0;
  double mean_edge_length = 0;
  /// Triangles by minimum angle, in 12 bins of 5° from 0° to 60°.
  std::array<long long, 12> min_angle_histogram{};
  double percent_below_10 = 0;  ///< % of triangles with minimum angle < 10°
  double percent_below_20 = 0;
  double percent_below_30 = 0;
  double mean_min_angle_deg = 0;
  double smallest_angle_deg = 0;
  /// Degenerate output, which the mesher never writes (a test sweeps for it): triangles of zero
  /// area, and vertices at the same point as another vertex.
  size_t zero_area_triangles = 0;
  size_t coincident_vertices = 0;
  double mean_radius_ratio = 0;  ///< 2 r_in / R_circ, 1 for an equilateral triangle
  double min_radius_ratio = 0;
  /// |F|/|∇F| at vertices outside the singular balls (first-order distance, Taubin 1991).
  double max_residual = 0;
  double rms_residual = 0;
  size_t residual_vertices = 0;  ///< vertices that entered the residual figures
  /// Vertices where F is not finite (singular balls included): never on F = 0, so when
  /// there are any, max_residual is the largest double.
  size_t undefined_vertices = 0;
  /// Angle between each face normal and ∇F at the face centroid, outside the singular balls.
  double mean_normal_deviation_deg = 0;
  double max_normal_deviation_deg = 0;
  size_t flipped_triangles = 0;  ///< of those, facing against ∇F (deviation > 90°)
  /// Largest |G| over the vertices flagged boundary (G the clip function).
  double max_boundary_clip_value = 0;
  size_t boundary_vertices = 0;
  double singular_radius = 0;  ///< the radius actually used
  /// Per known singular point inside the clip: the distance to the nearest vertex.
  std::vector<Vec3> singular_points;
  std::vector<double> singular_point_distance;
};

/// Measures a mesh against its surface. Known singular points come from
/// Surface::singular_points(). Cost: O(V + T) field evaluations, parallel.
MeshQuality measure_quality(const Mesh& mesh, const Surface& surface,
                            const QualityOptions& options = {});

struct DegenerateCount {
  size_t zero_area_triangles = 0;
  size_t coincident_vertices = 0;  ///< vertices at exactly the point of an earlier one
};
/// Counts degenerate output (no field evaluations): O(T + V log V).
DegenerateCount count_degenerate(const Mesh& mesh);

/// Minimum angle (degrees) and radius ratio of one triangle; 0 for a degenerate one.
double triangle_min_angle_deg(const Vec3& a, const Vec3& b, const Vec3& c);
double triangle_radius_ratio(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace zeroset
