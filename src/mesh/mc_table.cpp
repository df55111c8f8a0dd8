// Generates the marching cubes cycles from the face rule (see mc_table_detail.h): on each face
// a segment runs from a point where the sign changes from positive to negative (walking the
// face counter-clockwise seen from outside) to one where it changes back, so the positive
// side is on its left. Every edge point then has one outgoing and one incoming segment (its
// two faces walk the edge in opposite directions), and the segments close into cycles
// oriented counter-clockwise seen from the positive side.
//
// The table is built at compile time: a broken invariant (ZS_ASSERT) stops the compilation,
// and the polygonizer pays nothing for it at run time.
#include "mc_table_detail.h"
#include "zeroset/error.h"

namespace zeroset::detail {
namespace {

constexpr int edge_between(int a, int b) {
  for (int e = 0; e < 12; ++e) {
    const auto& c = kEdgeCorners[static_cast<std::size_t>(e)];
    if ((c[0] == a && c[1] == b) || (c[0] == b && c[1] == a)) return e;
  }
  ZS_ASSERT(false);
  return -1;
}

// Edge k of face f joins its corners kFaceCcw[f][k] and kFaceCcw[f][k + 1].
constexpr std::array<std::array<int, 4>, 6> kFaceEdges = [] {
  std::array<std::array<int, 4>, 6> edges{};
  for (int f = 0; f < 6; ++f)
    for (int k = 0; k < 4; ++k)
      edges[f][k] = edge_between(kFaceCcw[f][k], kFaceCcw[f][(k + 1) % 4]);
  return edges;
}();

constexpr CellPolygons build_cell(int cube_case, int connected) {
  auto positive = [&](int corner) { return ((cube_case >> corner) & 1) != 0; };
  std::array<int, 12> next{};
  next.fill(-1);
  for (int f = 0; f < 6; ++f) {
    const auto& q = kFaceCcw[f];
    const auto& edge = kFaceEdges[f];
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
        if (joined && !positive(q[k])) link(before, after);     // cut off each negative corner
        if (!joined && positive(q[k])) link(after, before);     // cut off each positive corner
      }
    }
  }
  CellPolygons cell;
  std::array<bool, 12> seen{};
  int written = 0;
  for (int start = 0; start < 12; ++start) {
    if (next[start] < 0 || seen[start]) continue;
    const int first = written;
    for (int e = start; !seen[e]; e = next[e]) {
      ZS_ASSERT(next[e] >= 0);
      seen[e] = true;
      cell.edges[written++] = static_cast<std::uint8_t>(e);
    }
    const int n = written - first;
    cell.cycle_length[cell.cycle_count++] = static_cast<std::uint8_t>(n);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) {
        const int gap = a < b ? b - a : a - b;
        const bool side = gap == 1 || gap == n - 1;
        if (a != b && (side || !edges_share_face(cell.edges[first + a], cell.edges[first + b])))
          cell.chords[first + a] = static_cast<std::uint16_t>(cell.chords[first + a] | 1u << b);
      }
  }
  return cell;
}

// The entries of cases [first, last). Resolution number r sets the t-th ambiguous face when
// bit t of r is set.
template <int kFirst, int kLast>
constexpr auto build_cases() {
  constexpr std::size_t offset = kCaseFirst[kFirst];
  std::array<CellPolygons, kCaseFirst[kLast] - offset> cells{};
  for (int c = kFirst; c < kLast; ++c) {
    const int amb = kAmbiguousFaces[static_cast<std::size_t>(c)];
    for (int r = 0; r < 1 << std::popcount(static_cast<unsigned>(amb)); ++r) {
      int connected = 0, t = 0;
      for (int f = 0; f < 6; ++f)
        if ((amb >> f) & 1) connected |= ((r >> t++) & 1) << f;
      cells[kCaseFirst[static_cast<std::size_t>(c)] - offset + static_cast<std::size_t>(r)] =
          build_cell(c, connected);
    }
  }
  return cells;
}

// Built in quarters: compilers bound the work of one constant expression (clang at a million
// steps), and the whole table takes about twice that.
constexpr auto kQuarter0 = build_cases<0, 64>();
constexpr auto kQuarter1 = build_cases<64, 128>();
constexpr auto kQuarter2 = build_cases<128, 192>();
constexpr auto kQuarter3 = build_cases<192, 256>();
constexpr std::array<CellPolygons, kCellEntries> kTable = [] {
  std::array<CellPolygons, kCellEntries> cells{};
  std::size_t at = 0;
  for (const auto& e : kQuarter0) cells[at++] = e;
  for (const auto& e : kQuarter1) cells[at++] = e;
  for (const auto& e : kQuarter2) cells[at++] = e;
  for (const auto& e : kQuarter3) cells[at++] = e;
  return cells;
}();

}  // namespace

const CellPolygons* cell_polygon_table() { return kTable.data(); }

}  // namespace zeroset::detail
