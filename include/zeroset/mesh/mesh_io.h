#pragma once
/// Mesh files: Wavefront OBJ, binary PLY, binary STL and glTF 2.0 binary (.glb).
///
/// Positions and normals are written as 32-bit floats in PLY, STL and glb (their usual form)
/// and with 9 significant digits in OBJ. PLY (through zeroset/io/ply.h) also carries the
/// per-vertex `boundary` flag.
/// STL has no shared vertices; reading one merges bitwise equal corners.
#include <string>
#include <vector>

#include "zeroset/mesh/mesh.h"

namespace zeroset {

/// The extensions `write_mesh` and `read_mesh` know: "obj", "ply", "stl", "glb".
const std::vector<std::string>& mesh_file_extensions();

/// Writes the mesh in the format its extension names (case-insensitive), atomically: on
/// any error no file is left at `path`. Throws InvalidArgument for an unknown extension
/// (listing the known ones) and IoError when the file cannot be written.
void write_mesh(const Mesh& mesh, const std::string& path);

/// Checks before long work that `path` has a known extension and can be written.
/// Throws like write_mesh.
void check_mesh_path(const std::string& path);

/// Reads a mesh written by `write_mesh` (OBJ with triangles or polygons, which are fanned;
/// PLY, ASCII or binary little-endian, with any scalar property types; binary STL; glb with one
/// triangle primitive). Throws IoError naming the path and what is wrong.
Mesh read_mesh(const std::string& path);

}  // namespace zeroset
