#include "zeroset/floaters/ply.h"

#include <fmt/core.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"

namespace zeroset {
namespace {

void put_float_le(std::ostream& out, double v) {
  const auto bits = std::bit_cast<std::uint32_t>(static_cast<float>(v));
  const char bytes[4] = {static_cast<char>(bits & 0xff), static_cast<char>((bits >> 8) & 0xff),
                         static_cast<char>((bits >> 16) & 0xff),
                         static_cast<char>((bits >> 24) & 0xff)};
  out.write(bytes, 4);
}

struct Property {
  std::string name;
  int size = 0;  // bytes in binary files
  bool is_float = false;
  bool is_signed = false;
};

int type_size(const std::string& type, bool& is_float, bool& is_signed) {
  static const std::map<std::string, std::tuple<int, bool, bool>> kTypes = {
      {"char", {1, false, true}},    {"int8", {1, false, true}},    {"uchar", {1, false, false}},
      {"uint8", {1, false, false}},  {"short", {2, false, true}},   {"int16", {2, false, true}},
      {"ushort", {2, false, false}}, {"uint16", {2, false, false}}, {"int", {4, false, true}},
      {"int32", {4, false, true}},   {"uint", {4, false, false}},   {"uint32", {4, false, false}},
      {"float", {4, true, true}},    {"float32", {4, true, true}},  {"double", {8, true, true}},
      {"float64", {8, true, true}}};
  const auto it = kTypes.find(type);
  if (it == kTypes.end()) return 0;
  is_float = std::get<1>(it->second);
  is_signed = std::get<2>(it->second);
  return std::get<0>(it->second);
}

double decode_le(const unsigned char* b, const Property& p) {
  std::uint64_t bits = 0;
  for (int k = p.size - 1; k >= 0; --k) bits = (bits << 8) | b[k];
  if (p.is_float)
    return p.size == 4 ? static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(bits)))
                       : std::bit_cast<double>(bits);
  if (!p.is_signed) return static_cast<double>(bits);
  const int shift = 64 - 8 * p.size;  // sign-extend
  return static_cast<double>(static_cast<std::int64_t>(bits << shift) >> shift);
}

}  // namespace

void write_points_ply(const std::string& path, std::span<const Vec3> positions,
                      std::span<const Vec3> normals, std::span<const double> radii,
                      PlyFormat format) {
  if (!normals.empty() && normals.size() != positions.size())
    throw InvalidArgument(fmt::format("write_points_ply: {} normals for {} points", normals.size(),
                                      positions.size()));
  if (!radii.empty() && radii.size() != positions.size())
    throw InvalidArgument(
        fmt::format("write_points_ply: {} radii for {} points", radii.size(), positions.size()));
  const bool binary = format == PlyFormat::kBinaryLittleEndian;
  write_file_atomically(path, [&](std::ostream& out) {
    out << "ply\nformat " << (binary ? "binary_little_endian" : "ascii") << " 1.0\n"
        << "comment zeroset floaters\n"
        << "element vertex " << positions.size() << "\n"
        << "property float x\nproperty float y\nproperty float z\n";
    if (!normals.empty()) out << "property float nx\nproperty float ny\nproperty float nz\n";
    if (!radii.empty()) out << "property float radius\n";
    out << "end_header\n";
    for (std::size_t i = 0; i < positions.size(); ++i) {
      if (binary) {
        for (int k = 0; k < 3; ++k) put_float_le(out, positions[i][k]);
        if (!normals.empty())
          for (int k = 0; k < 3; ++k) put_float_le(out, normals[i][k]);
        if (!radii.empty()) put_float_le(out, radii[i]);
        continue;
      }
      // %.9g round-trips a float exactly.
      out << fmt::format("{:.9g} {:.9g} {:.9g}", static_cast<float>(positions[i].x()),
                         static_cast<float>(positions[i].y()),
                         static_cast<float>(positions[i].z()));
      if (!normals.empty())
        out << fmt::format(" {:.9g} {:.9g} {:.9g}", static_cast<float>(normals[i].x()),
                           static_cast<float>(normals[i].y()), static_cast<float>(normals[i].z()));
      if (!radii.empty()) out << fmt::format(" {:.9g}", static_cast<float>(radii[i]));
      out << '\n';
    }
  });
}

PointSet read_points_ply(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot open for reading");
  auto fail = [&](const std::string& why) -> IoError { return IoError(path, why); };

  std::string line;
  if (!std::getline(in, line) || line != "ply") throw fail("not a PLY file (no 'ply' line)");
  bool binary = false, have_format = false, in_vertex = false;
  std::size_t count = 0;
  std::vector<Property> props;
  while (true) {
    if (!std::getline(in, line)) throw fail("header ends before 'end_header'");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string word;
    words >> word;
    if (word == "end_header") break;
    if (word == "comment" || word == "obj_info" || word.empty()) continue;
    if (word == "format") {
      std::string kind;
      words >> kind;
      if (kind == "ascii")
        binary = false;
      else if (kind == "binary_little_endian")
        binary = true;
      else
        throw fail("unsupported format '" + kind + "' (ascii or binary_little_endian)");
      have_format = true;
    } else if (word == "element") {
      std::string name;
      long long n = -1;
      words >> name >> n;
      if (name != "vertex") throw fail("unexpected element '" + name + "': only points are read");
      if (n < 0) throw fail("bad vertex count in '" + line + "'");
      count = static_cast<std::size_t>(n);
      in_vertex = true;
    } else if (word == "property") {
      if (!in_vertex) throw fail("property before 'element vertex'");
      std::string type, name;
      words >> type >> name;
      if (type == "list") throw fail("list properties are not supported in a point set");
      Property p;
      p.name = name;
      p.size = type_size(type, p.is_float, p.is_signed);
      if (p.size == 0) throw fail("unknown property type '" + type + "'");
      props.push_back(p);
    } else {
      throw fail("unexpected header line '" + line + "'");
    }
  }
  if (!have_format) throw fail("no format line");
  std::map<std::string, std::size_t> index;
  for (std::size_t k = 0; k < props.size(); ++k) index[props[k].name] = k;
  for (const char* need : {"x", "y", "z"})
    if (!index.count(need)) throw fail(std::string("no '") + need + "' property");
  const bool has_normals = index.count("nx") && index.count("ny") && index.count("nz");
  const bool has_radii = index.count("radius") > 0;

  PointSet ps;
  ps.positions.resize(count);
  if (has_normals) ps.normals.resize(count);
  if (has_radii) ps.radii.resize(count);
  std::size_t record = 0;
  for (const auto& p : props) record += static_cast<std::size_t>(p.size);
  std::vector<double> v(props.size());
  std::vector<unsigned char> bytes(record);
  for (std::size_t i = 0; i < count; ++i) {
    if (binary) {
      if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(record)))
        throw fail(fmt::format("truncated: vertex {} of {} missing", i, count));
      std::size_t offset = 0;
      for (std::size_t k = 0; k < props.size(); ++k) {
        v[k] = decode_le(bytes.data() + offset, props[k]);
        offset += static_cast<std::size_t>(props[k].size);
      }
    } else {
      for (std::size_t k = 0; k < props.size(); ++k)
        if (!(in >> v[k])) throw fail(fmt::format("vertex {} of {}: expected a number", i, count));
    }
    ps.positions[i] = Vec3(v[index["x"]], v[index["y"]], v[index["z"]]);
    if (has_normals) ps.normals[i] = Vec3(v[index["nx"]], v[index["ny"]], v[index["nz"]]);
    if (has_radii) ps.radii[i] = v[index["radius"]];
  }
  return ps;
}

}  // namespace zeroset
