#pragma once
// Marching cubes tables generated from first principles (no hand-typed case table): for every
// sign configuration of a cube and every resolution of its ambiguous faces, the oriented
// cycles of edge points that bound the surface inside the cube.
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>

namespace zeroset::detail {

// Corners in Lorensen's numbering: bit 0 is x, bit 1 ... see kCorner.
inline constexpr std::array<std::array<int, 3>, 8> kCorner = {
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}}};
// Each edge from its lower corner (the one owning it on the grid) to the upper one.
inline constexpr std::array<std::array<int, 2>, 12> kEdgeCorners = {{{0, 1},
                                                                     {1, 2},
                                                                     {3, 2},
                                                                     {0, 3},
                                                                     {4, 5},
                                                                     {5, 6},
                                                                     {7, 6},
                                                                     {4, 7},
                                                                     {0, 4},
                                                                     {1, 5},
                                                                     {2, 6},
                                                                     {3, 7}}};
inline constexpr std::array<int, 12> kEdgeAxis = {0, 1, 0, 1, 0, 1, 0, 1, 2, 2, 2, 2};
// Faces -x, +x, -y, +y, -z, +z: corners counter-clockwise seen from outside the cube.
inline constexpr std::array<std::array<int, 4>, 6> kFaceCcw = {
    {{0, 4, 7, 3}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 7, 6, 2}, {0, 3, 2, 1}, {4, 5, 6, 7}}};
// The same faces' corners at (u, v) = (0,0), (1,0), (1,1), (0,1), u and v the face's two
// axes in increasing order. Both cubes sharing a face see it in this order, so the
// asymptotic decider gives them bit-identical answers.
inline constexpr std::array<std::array<int, 4>, 6> kFaceCanonical = {
    {{0, 3, 7, 4}, {1, 2, 6, 5}, {0, 1, 5, 4}, {3, 2, 6, 7}, {0, 1, 2, 3}, {4, 5, 6, 7}}};

struct CellPolygons {
  std::uint8_t cycle_count = 0;
  std::array<std::uint8_t, 4> cycle_length{};
  std::array<std::uint8_t, 12> edges{};  // cycles one after the other, in orientation order
  // Bit b of chords[s + a], for the cycle whose points start at edges[s]: points a and b of
  // that cycle may be joined by a triangle side. Neighbours on the cycle always may; other
  // pairs may not when both points lie on one cube face, since such a diagonal lies in the
  // face and the neighbouring cube could use it too (a non-manifold edge). Tabulated here
  // so the triangulation of a cell does not test edge pairs.
  std::array<std::uint16_t, 12> chords{};
};

// Faces whose corners alternate in sign (bit f for face f) for a case (bit k: corner k ≥ 0).
inline constexpr std::array<std::uint8_t, 256> kAmbiguousFaces = [] {
  std::array<std::uint8_t, 256> amb{};
  for (int c = 0; c < 256; ++c)
    for (int f = 0; f < 6; ++f) {
      const auto& q = kFaceCcw[static_cast<std::size_t>(f)];
      const int s0 = (c >> q[0]) & 1, s1 = (c >> q[1]) & 1, s2 = (c >> q[2]) & 1,
                s3 = (c >> q[3]) & 1;
      if (s0 == s2 && s1 == s3 && s0 != s1)
        amb[static_cast<std::size_t>(c)] |= static_cast<std::uint8_t>(1 << f);
    }
  return amb;
}();
inline std::uint8_t ambiguous_faces(int cube_case) {
  return kAmbiguousFaces[static_cast<std::size_t>(cube_case)];
}
// Edges whose two corners differ in sign (bit e for edge e), per case.
inline constexpr std::array<std::uint16_t, 256> kCrossingEdges = [] {
  std::array<std::uint16_t, 256> mask{};
  for (int c = 0; c < 256; ++c)
    for (int e = 0; e < 12; ++e)
      if (((c >> kEdgeCorners[e][0]) & 1) != ((c >> kEdgeCorners[e][1]) & 1))
        mask[static_cast<std::size_t>(c)] =
            static_cast<std::uint16_t>(mask[static_cast<std::size_t>(c)] | 1u << e);
  return mask;
}();
// The table holds, for each case, one entry per resolution of its ambiguous faces (656 in
// all): case c's entries start at kCaseFirst[c], and the resolution is numbered by the
// ambiguous faces in increasing order, bit t set when the t-th one joins its positive corners.
inline constexpr std::array<std::uint16_t, 257> kCaseFirst = [] {
  std::array<std::uint16_t, 257> first{};
  for (std::size_t c = 0; c < 256; ++c)
    first[c + 1] = static_cast<std::uint16_t>(first[c] + (1 << std::popcount(kAmbiguousFaces[c])));
  return first;
}();
inline constexpr int kCellEntries = kCaseFirst[256];
// The number of a resolution among a case's entries: the bits of `connected` (bit f set when
// the positive corners of face f are joined) at the case's ambiguous faces, packed.
constexpr int ambiguous_rank(int cube_case, int connected) {
  const int amb = kAmbiguousFaces[static_cast<std::size_t>(cube_case)];
  int rank = 0, t = 0;
  for (int f = 0; f < 6; ++f)
    if ((amb >> f) & 1) rank |= ((connected >> f) & 1) << t++;
  return rank;
}
// The whole table (kCellEntries entries), built at compile time.
const CellPolygons* cell_polygon_table();
// The cycles for a case; `connected` has bit f set when the positive corners of face f are
// joined (saddle value ≥ 0). Bits of faces that are not ambiguous are ignored.
inline const CellPolygons& cell_polygons(int cube_case, int connected) {
  return cell_polygon_table()[kCaseFirst[static_cast<std::size_t>(cube_case)] +
                              ambiguous_rank(cube_case, connected)];
}
// Bit e2 of kFaceMates[e1] is set when edges e1 and e2 lie on one cube face.
inline constexpr std::array<std::uint16_t, 12> kFaceMates = [] {
  std::array<std::uint16_t, 12> mates{};
  for (const auto& q : kFaceCcw) {
    std::array<int, 4> edge{};
    for (int k = 0; k < 4; ++k) {
      const int a = q[k], b = q[(k + 1) % 4];
      for (int e = 0; e < 12; ++e)
        if ((kEdgeCorners[e][0] == a && kEdgeCorners[e][1] == b) ||
            (kEdgeCorners[e][0] == b && kEdgeCorners[e][1] == a))
          edge[k] = e;
    }
    for (int e1 : edge)
      for (int e2 : edge) mates[e1] = static_cast<std::uint16_t>(mates[e1] | 1u << e2);
  }
  return mates;
}();

// True when both edges lie on one cube face (a diagonal between them would lie in that face).
constexpr bool edges_share_face(int e1, int e2) {
  return (kFaceMates[static_cast<std::size_t>(e1)] >> e2) & 1;
}

// Asymptotic decider on a face's canonical corner values: true when the positive corners
// are connected through the face (the bilinear saddle value is ≥ 0).
inline bool positive_corners_connected(double v00, double v10, double v11, double v01) {
  const double num = v00 * v11 - v10 * v01;
  const double den = v00 + v11 - v10 - v01;
  return den > 0 ? num >= 0 : num <= 0;
}

}  // namespace zeroset::detail
