#include "zeroset/floaters/ply.h"

#include "zeroset/error.h"

namespace zeroset {

void write_points_ply(const std::string& path, std::span<const Vec3> positions,
                      std::span<const Vec3> normals, std::span<const double> radii,
                      PlyFormat format) {
  PlyContent c;
  c.comment = "zeroset floaters";
  c.positions = positions;
  c.normals = normals;
  if (!radii.empty()) c.properties.push_back({"radius", PlyScalar::kFloat, radii});
  write_ply(path, c, format);
}

PointSet read_points_ply(const std::string& path) {
  PlyData ply = read_ply(path);
  if (!ply.triangles.empty()) throw IoError(path, "has faces: a point set has none");
  PointSet ps;
  ps.positions = std::move(ply.positions);
  ps.normals = std::move(ply.normals);
  if (auto it = ply.properties.find("radius"); it != ply.properties.end())
    ps.radii = std::move(it->second);
  return ps;
}

}  // namespace zeroset
