#include "zeroset/floaters/ply.h"

#include <cmath>
#include <string>

#include "zeroset/error.h"

namespace zeroset {

void write_points_ply(const std::string& path, std::span<const Vec3> positions,
                      std::span<const Vec3> normals, std::span<const double> radii,
                      PlyFormat format) {
  // Readers cannot parse nan or inf: a point set with such a number is refused, not written.
  for (size_t i = 0; i < positions.size(); ++i)
    if (!positions[i].allFinite() || (i < normals.size() && !normals[i].allFinite()) ||
        (i < radii.size() && !std::isfinite(radii[i])))
      throw BadInput(path + ": floater " + std::to_string(i) +
                     " has a position, normal or radius that is not finite; nothing written");
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
