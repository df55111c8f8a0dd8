#pragma once
/// PLY files (the Stanford polygon format) as plain arrays: vertex positions with optional
/// normals and further scalar vertex properties, and optionally triangles. The mesh files and
/// the floaters' point sets are both written and read here.
///
/// Written: ASCII or binary little-endian; x y z [nx ny nz] and the further properties as
/// 32-bit floats (or unsigned bytes); faces as "list uchar uint vertex_indices".
/// Read: ASCII or binary little-endian with any scalar property type; polygons are fanned
/// into triangles.
#include <array>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "zeroset/types.h"

namespace zeroset {

enum class PlyFormat { kBinaryLittleEndian, kAscii };

/// How a further vertex property is stored: a 32-bit float, or an unsigned byte (a flag).
enum class PlyScalar { kFloat, kUChar };

/// One further per-vertex property to write, as long as the positions.
struct PlyProperty {
  std::string name;
  PlyScalar type = PlyScalar::kFloat;
  std::span<const double> values;
};

/// What write_ply writes. The spans must stay alive during the call.
struct PlyContent {
  std::string comment;                  ///< one "comment" header line (none when empty)
  std::span<const Vec3> positions;      ///< x y z
  std::span<const Vec3> normals;        ///< nx ny nz: empty (left out) or one per position
  std::vector<PlyProperty> properties;  ///< written after the normals, in this order
  bool has_faces = false;               ///< writes a face element, even an empty one
  std::span<const std::array<std::uint32_t, 3>> triangles;  ///< only with has_faces
  /// An "edge" element (vertex1, vertex2), left out when empty: polylines such as a mesh's
  /// singular curves. `edge_kinds` empty or one uchar "kind" per edge.
  std::span<const std::array<std::uint32_t, 2>> edges;
  std::span<const std::uint8_t> edge_kinds;
};

/// Writes `content` atomically: on any error no file is left at `path`. Throws
/// InvalidArgument when a normal or property count differs from the position count or a
/// triangle refers to a missing vertex (before anything is written), IoError when the file
/// cannot be written.
void write_ply(const std::string& path, const PlyContent& content,
               PlyFormat format = PlyFormat::kBinaryLittleEndian);

/// A PLY file read back.
struct PlyData {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  ///< empty when the file has no nx, ny, nz
  /// The other scalar vertex properties by name (radius, boundary, ...), one value per vertex.
  std::map<std::string, std::vector<double>> properties;
  bool has_faces = false;  ///< the file has a face element (perhaps an empty one)
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< faces, polygons fanned
  std::vector<std::array<std::uint32_t, 2>> edges;      ///< the "edge" element's vertex1, vertex2
};

/// Reads a PLY file with a "vertex" element (x, y, z required) and optionally a "face"
/// element (one list property of vertex indices; its scalar properties are skipped) and an
/// "edge" element (vertex1, vertex2; other properties skipped). Other
/// non-empty elements and list properties of vertices are refused. Throws IoError naming the
/// path and what is wrong.
PlyData read_ply(const std::string& path);

}  // namespace zeroset
