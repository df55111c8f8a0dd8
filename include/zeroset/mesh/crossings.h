#pragma once
/// Singular curves in meshes: where two sheets of F = 0 cross along a curve, marching cubes
/// joins the four half-sheets in pairs and rounds them off a cell away from the curve. This
/// step makes the crossing true: it finds the singular set, cuts the mesh in a thin tube
/// around every crossing curve and joins each half-sheet to the curve's polyline, whose
/// vertices lie on the curve. Afterwards every edge of a double curve is shared by four
/// triangles (six on a triple line), pinch and triple points are vertices, and isolated real
/// curves (no sheet through them) are added as vertex chains without triangles. The method,
/// with its constants, is in docs/meshing.md ("Crossings").
#include <stop_token>
#include <string>
#include <vector>

#include "zeroset/mesh/mesh.h"
#include "zeroset/surface/singular_set.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

struct CrossingOptions {
  /// Triangles with a corner closer than this many grid cells to a crossing curve are replaced.
  /// At √3 (a cell's diagonal) no kept triangle lies in a cell the curve passes through.
  double tube_cells = 1.8;
  /// Spacing of the curve's vertices in mean edge lengths of the input mesh.
  double spacing_edges = 1.0;
  /// Edges of the joining strips longer than this many mean edge lengths are split.
  double split_edges = 1.8;
  /// Add isolated real curves to `Mesh::curves` (they are written as polylines).
  bool isolated_curves = true;
  /// Seed grid of the singular-set search; 0: half the mesh's cells, within [48, 96].
  int search_cells = 0;
};

struct CrossingStats {
  int crossing_curves = 0;
  int isolated_curves = 0;
  long long curve_vertices = 0;     ///< vertices added on curves
  long long removed_triangles = 0;  ///< marching-cubes triangles in the tubes
  long long added_triangles = 0;    ///< triangles joining the half-sheets to the curves
  long long strip_vertices = 0;     ///< vertices added inside the strips (split long edges)
  /// A ball where a cut could not be joined to the curves: the mesh inside is left as marching
  /// cubes made it (the sheets rounded off there); every other crossing is treated.
  struct Place {
    Vec3 at = Vec3::Zero();
    double radius = 0;
  };
  std::vector<Place> left_as_marching_cubes;
  /// Why the crossings were left as marching cubes made them everywhere (empty: they were
  /// not). The mesh is then unchanged apart from the isolated curves.
  std::string failure;
  double seconds = 0;
};

/// Makes the crossings of `mesh` (from `polygonize` at grid cell size `cell_size`) true, as
/// described above, and returns what it did; the singular set it used (traced at the mesh's
/// edge length) is stored in `*set` when given. A surface without singular curves costs one
/// singular-set search (milliseconds) and leaves the mesh as it is. Throws what
/// find_singular_set throws.
CrossingStats mesh_crossings(Mesh& mesh, const Surface& surface, double cell_size,
                             const CrossingOptions& options = {}, SingularSet* set = nullptr,
                             std::stop_token stop = {});

}  // namespace zeroset
