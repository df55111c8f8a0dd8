#pragma once
/// Small mesh operations shared by the polygonizer, the improver and the front ends.
#include <cstddef>

#include "zeroset/mesh/mesh.h"
#include "zeroset/surface/surface.h"

namespace zeroset {

/// Drops vertices no triangle and no curve uses and renumbers the rest (order kept). Keeps
/// `is_boundary` and `normals` in step when they have one entry per vertex. Returns how many were
/// dropped.
size_t remove_unreferenced_vertices(Mesh& mesh);

/// Removes degenerate triangles by collapsing every edge shorter than `min_length` (shortest
/// first), so the mesh stays watertight where it was: an edge is collapsed only when the link
/// condition holds (the two end points share exactly the neighbours of the one or two
/// triangles on the edge), no remaining triangle turns over or loses all its area, and an
/// interior edge between two boundary vertices is kept. A boundary vertex keeps its position
/// (it lies on the clip surface). Triangles with a repeated vertex are dropped first.
/// Returns the number of collapsed edges. Cost: O(V + T) plus a little per short edge.
size_t collapse_short_edges(Mesh& mesh, double min_length);

/// Sets `mesh.normals` to ∇F/|∇F| at every vertex (batched evaluation, parallel). Where ∇F
/// vanishes or is not finite (singular points) the normalised sum of the area-weighted
/// normals of the incident triangles is used instead. `threads` 0: all cores.
void compute_field_normals(Mesh& mesh, const Surface& surface, int threads = 0);

}  // namespace zeroset
