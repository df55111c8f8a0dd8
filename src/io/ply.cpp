#include "zeroset/io/ply.h"

#include <fmt/format.h>

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <string_view>

#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"

namespace zeroset {
namespace {

// ---- writing -------------------------------------------------------------------------------

// Little-endian bytes independent of the host's byte order.
void put_u8(std::string& out, std::uint8_t v) { out.push_back(static_cast<char>(v)); }
void put_u32(std::string& out, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) put_u8(out, static_cast<std::uint8_t>(v >> (8 * k)));
}
void put_f32(std::string& out, double v) {
  put_u32(out, std::bit_cast<std::uint32_t>(static_cast<float>(v)));
}

void check_content(const PlyContent& c) {
  const std::size_t n = c.positions.size();
  if (!c.normals.empty() && c.normals.size() != n)
    throw InvalidArgument(
        fmt::format("write_ply: {} normals for {} vertices", c.normals.size(), n));
  for (const PlyProperty& p : c.properties)
    if (p.values.size() != n)
      throw InvalidArgument(
          fmt::format("write_ply: {} values of '{}' for {} vertices", p.values.size(), p.name, n));
  for (const auto& t : c.triangles)
    for (std::uint32_t v : t)
      if (v >= n)
        throw InvalidArgument(fmt::format("write_ply: a triangle refers to vertex {} of {}", v, n));
  for (const auto& e : c.edges)
    for (std::uint32_t v : e)
      if (v >= n)
        throw InvalidArgument(fmt::format("write_ply: an edge refers to vertex {} of {}", v, n));
  if (!c.edge_kinds.empty() && c.edge_kinds.size() != c.edges.size())
    throw InvalidArgument(
        fmt::format("write_ply: {} edge kinds for {} edges", c.edge_kinds.size(), c.edges.size()));
  // Every number is written as a float: one that is not finite, or does not fit (|v| above
  // 3.4e38 becomes inf), is refused rather than written as a word no reader parses.
  auto fits = [](double v) { return std::abs(v) <= std::numeric_limits<float>::max(); };
  for (std::size_t i = 0; i < n; ++i) {
    const bool ok = fits(c.positions[i].x()) && fits(c.positions[i].y()) &&
                    fits(c.positions[i].z()) &&
                    (c.normals.empty() ||
                     (fits(c.normals[i].x()) && fits(c.normals[i].y()) && fits(c.normals[i].z())));
    if (!ok)
      throw BadInput(
          fmt::format("write_ply: vertex {} has a coordinate or normal that is not "
                      "finite or beyond a float's range; nothing written",
                      i));
    for (const PlyProperty& p : c.properties)
      if (p.type == PlyScalar::kFloat && !fits(p.values[i]))
        throw BadInput(
            fmt::format("write_ply: the {} of vertex {} is not finite or beyond a "
                        "float's range ({}); nothing written",
                        p.name, i, p.values[i]));
  }
}

std::string header(const PlyContent& c, bool binary) {
  std::string h = "ply\nformat ";
  h += binary ? "binary_little_endian" : "ascii";
  h += " 1.0\n";
  if (!c.comment.empty()) h += "comment " + c.comment + "\n";
  h += fmt::format("element vertex {}\n", c.positions.size());
  h += "property float x\nproperty float y\nproperty float z\n";
  if (!c.normals.empty()) h += "property float nx\nproperty float ny\nproperty float nz\n";
  for (const PlyProperty& p : c.properties)
    h += fmt::format("property {} {}\n", p.type == PlyScalar::kFloat ? "float" : "uchar", p.name);
  if (c.has_faces)
    h += fmt::format("element face {}\nproperty list uchar uint vertex_indices\n",
                     c.triangles.size());
  if (!c.edges.empty()) {
    h += fmt::format("element edge {}\nproperty int vertex1\nproperty int vertex2\n",
                     c.edges.size());
    if (!c.edge_kinds.empty()) h += "property uchar kind\n";
  }
  h += "end_header\n";
  return h;
}

std::string binary_body(const PlyContent& c) {
  std::string b;
  std::size_t record = 12 + (c.normals.empty() ? 0 : 12);
  for (const PlyProperty& p : c.properties) record += p.type == PlyScalar::kFloat ? 4 : 1;
  b.reserve(c.positions.size() * record + (c.has_faces ? c.triangles.size() * 13 : 0));
  for (std::size_t i = 0; i < c.positions.size(); ++i) {
    for (int k = 0; k < 3; ++k) put_f32(b, c.positions[i][k]);
    if (!c.normals.empty())
      for (int k = 0; k < 3; ++k) put_f32(b, c.normals[i][k]);
    for (const PlyProperty& p : c.properties) {
      if (p.type == PlyScalar::kFloat)
        put_f32(b, p.values[i]);
      else
        put_u8(b, static_cast<std::uint8_t>(p.values[i]));
    }
  }
  if (c.has_faces)
    for (const auto& t : c.triangles) {
      put_u8(b, 3);
      for (std::uint32_t v : t) put_u32(b, v);
    }
  for (std::size_t e = 0; e < c.edges.size(); ++e) {
    put_u32(b, c.edges[e][0]);
    put_u32(b, c.edges[e][1]);
    if (!c.edge_kinds.empty()) put_u8(b, c.edge_kinds[e]);
  }
  return b;
}

std::string ascii_body(const PlyContent& c) {
  fmt::memory_buffer out;
  auto put = std::back_inserter(out);
  // %.9g round-trips a float exactly.
  for (std::size_t i = 0; i < c.positions.size(); ++i) {
    const Vec3& p = c.positions[i];
    fmt::format_to(put, "{:.9g} {:.9g} {:.9g}", static_cast<float>(p.x()),
                   static_cast<float>(p.y()), static_cast<float>(p.z()));
    if (!c.normals.empty()) {
      const Vec3& n = c.normals[i];
      fmt::format_to(put, " {:.9g} {:.9g} {:.9g}", static_cast<float>(n.x()),
                     static_cast<float>(n.y()), static_cast<float>(n.z()));
    }
    for (const PlyProperty& q : c.properties) {
      if (q.type == PlyScalar::kFloat)
        fmt::format_to(put, " {:.9g}", static_cast<float>(q.values[i]));
      else
        fmt::format_to(put, " {}", static_cast<unsigned>(static_cast<std::uint8_t>(q.values[i])));
    }
    out.push_back('\n');
  }
  if (c.has_faces)
    for (const auto& t : c.triangles) fmt::format_to(put, "3 {} {} {}\n", t[0], t[1], t[2]);
  for (std::size_t e = 0; e < c.edges.size(); ++e) {
    fmt::format_to(put, "{} {}", c.edges[e][0], c.edges[e][1]);
    if (!c.edge_kinds.empty()) fmt::format_to(put, " {}", static_cast<unsigned>(c.edge_kinds[e]));
    out.push_back('\n');
  }
  return fmt::to_string(out);
}

// ---- reading -------------------------------------------------------------------------------

struct Scalar {
  int size = 0;  // bytes in binary files
  bool is_float = false;
  bool is_signed = false;
};

// Returns size 0 for an unknown type name.
Scalar scalar_type(std::string_view type) {
  struct Named {
    std::string_view name;
    Scalar scalar;
  };
  static constexpr Named kTypes[] = {
      {"char", {1, false, true}},    {"int8", {1, false, true}},    {"uchar", {1, false, false}},
      {"uint8", {1, false, false}},  {"short", {2, false, true}},   {"int16", {2, false, true}},
      {"ushort", {2, false, false}}, {"uint16", {2, false, false}}, {"int", {4, false, true}},
      {"int32", {4, false, true}},   {"uint", {4, false, false}},   {"uint32", {4, false, false}},
      {"float", {4, true, true}},    {"float32", {4, true, true}},  {"double", {8, true, true}},
      {"float64", {8, true, true}}};
  for (const Named& t : kTypes)
    if (t.name == type) return t.scalar;
  return {};
}

struct Property {
  std::string name;
  Scalar type;
  bool is_list = false;
  Scalar count_type;  // of a list
};

struct Element {
  std::string name;
  std::size_t count = 0;
  std::vector<Property> properties;
};

// The numbers after the header, one at a time, from a binary or an ASCII body.
class Body {
 public:
  Body(const std::string& path, const std::string& data, std::size_t at, bool binary)
      : path_(path), data_(data), at_(at), binary_(binary) {}

  [[noreturn]] void fail(const std::string& why) const { throw IoError(path_, why); }

  // The record being read, for error messages ("vertex 3 of 10").
  void at_record(const char* element, std::size_t i, std::size_t count) {
    element_ = element, record_ = i, count_ = count;
  }
  [[noreturn]] void fail_record(const std::string& why) const {
    fail(fmt::format("{} {} of {}: {}", element_, record_, count_, why));
  }

  double next(const Scalar& t) { return binary_ ? next_binary(t) : next_ascii(); }

 private:
  double next_binary(const Scalar& t) {
    const auto size = static_cast<std::size_t>(t.size);
    if (size > data_.size() - at_) fail_record("truncated, the file ends");
    std::uint64_t bits = 0;
    for (std::size_t k = size; k-- > 0;)
      bits = (bits << 8) | static_cast<unsigned char>(data_[at_ + k]);
    at_ += size;
    if (t.is_float)
      return t.size == 4
                 ? static_cast<double>(std::bit_cast<float>(static_cast<std::uint32_t>(bits)))
                 : std::bit_cast<double>(bits);
    if (!t.is_signed) return static_cast<double>(bits);
    const int shift = 64 - 8 * t.size;  // sign-extend
    return static_cast<double>(static_cast<std::int64_t>(bits << shift) >> shift);
  }

  double next_ascii() {
    const char* begin = data_.c_str() + at_;
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(begin, &end);
    if (end == begin) fail_record("expected a number");
    at_ += static_cast<std::size_t>(end - begin);
    return v;
  }

  const std::string& path_;
  const std::string& data_;
  std::size_t at_;
  bool binary_;
  const char* element_ = "";
  std::size_t record_ = 0, count_ = 0;
};

}  // namespace

void write_ply(const std::string& path, const PlyContent& content, PlyFormat format) {
  check_content(content);
  const bool binary = format == PlyFormat::kBinaryLittleEndian;
  const std::string head = header(content, binary);
  const std::string body = binary ? binary_body(content) : ascii_body(content);
  write_file_atomically(path, [&](std::ostream& out) {
    out.write(head.data(), static_cast<std::streamsize>(head.size()));
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
  });
}

PlyData read_ply(const std::string& path) {
  const std::string data = read_text_file(path);
  auto fail = [&](const std::string& why) -> IoError { return IoError(path, why); };

  // Header: one line at a time up to end_header.
  std::size_t at = 0;
  auto next_line = [&](std::string& line) {
    if (at >= data.size()) return false;
    std::size_t eol = data.find('\n', at);
    if (eol == std::string::npos) eol = data.size();
    line.assign(data, at, eol - at);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    at = eol + 1;
    return true;
  };
  std::string line;
  if (!next_line(line) || line != "ply") throw fail("not a PLY file (no 'ply' line)");
  bool binary = false, have_format = false;
  std::vector<Element> elements;
  while (true) {
    if (!next_line(line)) throw fail("header ends before 'end_header'");
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
      Element e;
      long long n = -1;
      words >> e.name >> n;
      if (n < 0) throw fail("bad element count in '" + line + "'");
      e.count = static_cast<std::size_t>(n);
      elements.push_back(e);
    } else if (word == "property") {
      if (elements.empty()) throw fail("property before any element");
      Property p;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type;
        words >> count_type >> type;
        p.is_list = true;
        p.count_type = scalar_type(count_type);
        if (p.count_type.size == 0 || p.count_type.is_float)
          throw fail("bad list count type '" + count_type + "'");
      }
      words >> p.name;
      p.type = scalar_type(type);
      if (p.type.size == 0) throw fail("unknown property type '" + type + "'");
      elements.back().properties.push_back(p);
    } else {
      throw fail("unexpected header line '" + line + "'");
    }
  }
  if (!have_format) throw fail("no format line");

  PlyData ply;
  bool have_vertices = false;
  Body body(path, data, std::min(at, data.size()), binary);
  for (const Element& e : elements) {
    if (e.name == "vertex") {
      if (have_vertices) throw fail("two vertex elements");
      have_vertices = true;
      std::map<std::string, std::size_t> index;
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        if (e.properties[k].is_list) throw fail("list properties of vertices are not supported");
        index[e.properties[k].name] = k;
      }
      for (const char* need : {"x", "y", "z"})
        if (!index.count(need)) throw fail(std::string("no '") + need + "' property");
      const bool has_normals = index.count("nx") && index.count("ny") && index.count("nz");
      const std::size_t x = index["x"], y = index["y"], z = index["z"];
      const std::size_t nx = has_normals ? index["nx"] : 0, ny = has_normals ? index["ny"] : 0,
                        nz = has_normals ? index["nz"] : 0;
      ply.positions.resize(e.count);
      if (has_normals) ply.normals.resize(e.count);
      std::vector<std::pair<std::vector<double>*, std::size_t>> others;
      for (const auto& [name, k] : index) {
        const bool normal = name == "nx" || name == "ny" || name == "nz";
        if (name == "x" || name == "y" || name == "z" || (has_normals && normal)) continue;
        auto& values = ply.properties[name];
        values.resize(e.count);
        others.emplace_back(&values, k);
      }
      std::vector<double> v(e.properties.size());
      for (std::size_t i = 0; i < e.count; ++i) {
        body.at_record("vertex", i, e.count);
        for (std::size_t k = 0; k < e.properties.size(); ++k)
          v[k] = body.next(e.properties[k].type);
        ply.positions[i] = Vec3(v[x], v[y], v[z]);
        if (has_normals) ply.normals[i] = Vec3(v[nx], v[ny], v[nz]);
        for (auto& [values, k] : others) (*values)[i] = v[k];
      }
    } else if (e.name == "face") {
      ply.has_faces = true;
      std::vector<std::uint32_t> idx;
      for (std::size_t f = 0; f < e.count; ++f) {
        body.at_record("face", f, e.count);
        for (const Property& p : e.properties) {
          if (!p.is_list) {
            body.next(p.type);  // a scalar face property: skipped
            continue;
          }
          const double n = body.next(p.count_type);
          if (!(n >= 0 && n < 65536)) body.fail_record("bad list length");
          const bool indices = p.name == "vertex_indices" || p.name == "vertex_index";
          idx.clear();
          for (int k = 0; k < static_cast<int>(n); ++k) {
            const double i = body.next(p.type);
            if (!indices) continue;
            if (!(i >= 0 && i < 4294967296.0)) body.fail_record("bad vertex index");
            idx.push_back(static_cast<std::uint32_t>(i));
          }
          if (!indices) continue;
          if (idx.size() < 3) body.fail_record("fewer than three vertices");
          for (std::size_t k = 1; k + 1 < idx.size(); ++k)
            ply.triangles.push_back({idx[0], idx[k], idx[k + 1]});
        }
      }
    } else if (e.name == "edge") {
      std::size_t v1 = e.properties.size(), v2 = v1;
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        if (e.properties[k].is_list) throw fail("list properties of edges are not supported");
        if (e.properties[k].name == "vertex1") v1 = k;
        if (e.properties[k].name == "vertex2") v2 = k;
      }
      if (e.count > 0 && (v1 == e.properties.size() || v2 == v1))
        throw fail("an edge element needs vertex1 and vertex2");
      std::vector<double> v(e.properties.size());
      for (std::size_t i = 0; i < e.count; ++i) {
        body.at_record("edge", i, e.count);
        for (std::size_t k = 0; k < e.properties.size(); ++k)
          v[k] = body.next(e.properties[k].type);
        for (double x : {v[v1], v[v2]})
          if (!(x >= 0 && x < 4294967296.0)) body.fail_record("bad vertex index");
        ply.edges.push_back({static_cast<std::uint32_t>(v[v1]), static_cast<std::uint32_t>(v[v2])});
      }
    } else if (e.count > 0) {
      throw fail("unsupported element '" + e.name + "' (vertex, face and edge are read)");
    }
  }
  if (!have_vertices) throw fail("no vertex element");
  for (const auto& t : ply.triangles)
    for (std::uint32_t v : t)
      if (v >= ply.positions.size())
        throw fail(fmt::format("a face refers to vertex {} of {}", v, ply.positions.size()));
  for (const auto& ed : ply.edges)
    for (std::uint32_t v : ed)
      if (v >= ply.positions.size())
        throw fail(fmt::format("an edge refers to vertex {} of {}", v, ply.positions.size()));
  return ply;
}

}  // namespace zeroset
