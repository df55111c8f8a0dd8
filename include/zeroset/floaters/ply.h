#pragma once
/// Point sets (floaters) as PLY files: vertex x, y, z, and optionally nx, ny, nz and radius.
/// The file format itself is zeroset/io/ply.h; these two functions name the floaters' columns.
#include <span>
#include <string>
#include <vector>

#include "zeroset/io/ply.h"
#include "zeroset/types.h"

namespace zeroset {

/// Writes a "vertex" element with float properties x y z [nx ny nz] [radius]. `normals` and
/// `radii` are either empty (property left out) or as long as `positions` (else
/// InvalidArgument). Written atomically: on error the file is untouched. Throws IoError.
void write_points_ply(const std::string& path, std::span<const Vec3> positions,
                      std::span<const Vec3> normals = {}, std::span<const double> radii = {},
                      PlyFormat format = PlyFormat::kBinaryLittleEndian);

/// A point set read back from a PLY file.
struct PointSet {
  std::vector<Vec3> positions;
  std::vector<Vec3> normals;  ///< empty when the file has no nx, ny, nz
  std::vector<double> radii;  ///< empty when the file has no radius
};

/// Reads what write_points_ply writes (ASCII or binary little-endian, any scalar property
/// types, other vertex properties ignored, faces not allowed). Throws IoError naming the path
/// and what is wrong.
PointSet read_points_ply(const std::string& path);

}  // namespace zeroset
