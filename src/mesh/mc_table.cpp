// Generates the marching cubes cycles from the face rule (see mc_table_detail.h): on each face
// a segment runs from a point where the sign changes from positive to negative (walking the
// face counter-clockwise seen from outside) to one where it changes back, so the positive
// side is on its left. Every edge point then has one outgoing and one incoming segment (its
// two faces walk the edge in opposite directions), and the segments close into cycles
// oriented counter-clockwise seen from the positive side.
#include <vector>

#include "mc_table_detail.h"
#include "zeroset/error.h"

namespace zeroset::detail {
namespace {

int edge_between(int a, int b) {
  for (int e = 0; e < 12; ++e) {
    const auto& c = kEdgeCorners[e];
    if ((c[0] == a && c[1] == b) || (c[0] == b && c[1] == a)) return e;
  }
  ZS_ASSERT(false);
  return -1;
}

CellPolygons build_cell(int cube_case, int connected) {
  auto positive = [&](int corner) { return ((cube_case >> corner) & 1) != 0; };
  std::array<int, 12> next;
  next.fill(-1);
  for (int f = 0; f < 6; ++f) {
    const auto& q = kFaceCcw[f];
    std::array<int, 4> edge{};  // edge k joins q[k] and q[k+1]
    for (int k = 0; k < 4; ++k) edge[k] = edge_between(q[k], q[(k + 1) % 4]);
    int changes = 0;
    for (int k = 0; k < 4; ++k) changes += positive(q[k]) != positive(q[(k + 1) % 4]);
    auto link = [&](int from, int to) {
      ZS_ASSERT(next[from] == -1);
      next[from] = to;
    };
    if (changes == 2) {
      int from = -1, to = -1;
      for (int k = 0; k < 4; ++k) {
        if (positive(q[k]) == positive(q[(k + 1) % 4])) continue;
        (positive(q[k]) ? from : to) = edge[k];
      }
      link(from, to);
    } else if (changes == 4) {
      const bool joined = ((connected >> f) & 1) != 0;
      for (int k = 0; k < 4; ++k) {
        const int before = edge[(k + 3) % 4], after = edge[k];  // edges into and out of q[k]
        if (joined && !positive(q[k])) link(before, after);    // cut off each negative corner
        if (!joined && positive(q[k])) link(after, before);    // cut off each positive corner
      }
    }
  }
  CellPolygons cell;
  std::array<bool, 12> seen{};
  int written = 0;
  for (int start = 0; start < 12; ++start) {
    if (next[start] < 0 || seen[start]) continue;
    int length = 0;
    for (int e = start; !seen[e]; e = next[e]) {
      ZS_ASSERT(next[e] >= 0);
      seen[e] = true;
      cell.edges[written++] = static_cast<std::uint8_t>(e);
      ++length;
    }
    cell.cycle_length[cell.cycle_count++] = static_cast<std::uint8_t>(length);
  }
  return cell;
}

struct Tables {
  std::vector<CellPolygons> cells;  // [case * 64 + connected]

  Tables() : cells(256 * 64) {
    for (int c = 0; c < 256; ++c) {
      // Only the resolutions of faces that are ambiguous differ (lookups mask the rest): build
      // each subset of the ambiguous faces once, a few hundred cells instead of 16,384.
      const int amb = kAmbiguousFaces[static_cast<size_t>(c)];
      for (int d = amb;; d = (d - 1) & amb) {
        cells[static_cast<size_t>(c * 64 + d)] = build_cell(c, d);
        if (d == 0) break;
      }
    }
  }
};

const Tables& tables() {
  static const Tables t;
  return t;
}

}  // namespace

const CellPolygons* cell_polygon_table() { return tables().cells.data(); }

const CellPolygons& cell_polygons(int cube_case, int connected) {
  return cell_polygon_table()[cube_case * 64 + (connected & ambiguous_faces(cube_case))];
}

}  // namespace zeroset::detail
