#include "zeroset/mesh/mesh_io.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <string_view>

#include <fmt/format.h>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "zeroset/error.h"
#include "zeroset/io/atomic_file.h"
#include "zeroset/io/ply.h"
#include "zeroset/surface/json_read.h"

namespace zeroset {
namespace {

// Little-endian byte output independent of the host's byte order.
class Bytes {
 public:
  void u8(std::uint8_t v) { data_.push_back(static_cast<char>(v)); }
  void u16(std::uint16_t v) {
    u8(static_cast<std::uint8_t>(v)), u8(static_cast<std::uint8_t>(v >> 8));
  }
  void u32(std::uint32_t v) {
    for (int k = 0; k < 4; ++k) u8(static_cast<std::uint8_t>(v >> (8 * k)));
  }
  void f32(double v) { u32(std::bit_cast<std::uint32_t>(static_cast<float>(v))); }
  void text(std::string_view s) { data_.append(s); }
  void pad(size_t multiple, char c) {
    while (data_.size() % multiple) data_.push_back(c);
  }
  size_t size() const { return data_.size(); }
  const std::string& str() const { return data_; }
  void reserve(size_t n) { data_.reserve(n); }

 private:
  std::string data_;
};

bool has_normals(const Mesh& m) {
  return !m.normals.empty() && m.normals.size() == m.positions.size();
}

Vec3 face_normal(const Mesh& m, const std::array<std::uint32_t, 3>& t) {
  const Vec3 n =
      (m.positions[t[1]] - m.positions[t[0]]).cross(m.positions[t[2]] - m.positions[t[0]]);
  const double len = n.norm();
  return len > 0 ? Vec3(n / len) : Vec3::Zero();
}

std::string obj_bytes(const Mesh& m) {
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "# zeroset mesh: {} vertices, {} triangles\n",
                 m.positions.size(), m.triangles.size());
  for (const Vec3& p : m.positions)
    fmt::format_to(std::back_inserter(out), "v {} {} {}\n", p.x(), p.y(), p.z());
  const bool normals = has_normals(m);
  if (normals)
    for (const Vec3& n : m.normals)
      fmt::format_to(std::back_inserter(out), "vn {:.6g} {:.6g} {:.6g}\n", n.x(), n.y(), n.z());
  for (const auto& t : m.triangles) {
    if (normals)
      fmt::format_to(std::back_inserter(out), "f {0}//{0} {1}//{1} {2}//{2}\n", t[0] + 1, t[1] + 1,
                     t[2] + 1);
    else
      fmt::format_to(std::back_inserter(out), "f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
  }
  // Singular curves as polylines; readers that want triangles only skip `l` lines.
  for (const MeshCurve& c : m.curves) {
    fmt::format_to(std::back_inserter(out), "# {} curve\nl", to_string(c.kind));
    for (std::uint32_t v : c.vertices) fmt::format_to(std::back_inserter(out), " {}", v + 1);
    out.push_back('\n');
  }
  return fmt::to_string(out);
}

// The boundary flags go to the PLY file as a "boundary" uchar property.
void write_ply_mesh(const Mesh& m, const std::string& path) {
  const bool flags = m.is_boundary.size() == m.positions.size();
  const std::vector<double> boundary(m.is_boundary.begin(),
                                     flags ? m.is_boundary.end() : m.is_boundary.begin());
  PlyContent c;
  c.comment = "zeroset mesh";
  c.positions = m.positions;
  if (has_normals(m)) c.normals = m.normals;
  if (flags) c.properties.push_back({"boundary", PlyScalar::kUChar, boundary});
  c.has_faces = true;
  c.triangles = m.triangles;
  // Singular curves as an edge element; "kind" is the CurveKind (0 crossing, 1 isolated).
  std::vector<std::array<std::uint32_t, 2>> edges;
  std::vector<std::uint8_t> kinds;
  for (const MeshCurve& mc : m.curves)
    for (size_t k = 0; k + 1 < mc.vertices.size(); ++k) {
      edges.push_back({mc.vertices[k], mc.vertices[k + 1]});
      kinds.push_back(static_cast<std::uint8_t>(mc.kind));
    }
  c.edges = edges;
  c.edge_kinds = kinds;
  write_ply(path, c);
}

std::string stl_bytes(const Mesh& m) {
  Bytes b;
  b.reserve(84 + 50 * m.triangles.size());
  std::string header = "zeroset mesh";
  header.resize(80, ' ');
  b.text(header);
  b.u32(static_cast<std::uint32_t>(m.triangles.size()));
  for (const auto& t : m.triangles) {
    const Vec3 n = face_normal(m, t);
    for (int k = 0; k < 3; ++k) b.f32(n[k]);
    for (std::uint32_t v : t)
      for (int k = 0; k < 3; ++k) b.f32(m.positions[v][k]);
    b.u16(0);
  }
  return b.str();
}

/// The glTF binary container: the JSON chunk (padded with spaces), then the BIN chunk unless
/// `bin` is empty (glTF allows no empty buffer).
std::string glb_container(const nlohmann::json& doc, const Bytes& bin) {
  Bytes js;
  js.text(doc.dump());
  js.pad(4, ' ');
  const size_t bin_chunk = bin.size() > 0 ? 8 + bin.size() : 0;
  Bytes out;
  out.u32(0x46546C67u);  // "glTF"
  out.u32(2);
  out.u32(static_cast<std::uint32_t>(12 + 8 + js.size() + bin_chunk));
  out.u32(static_cast<std::uint32_t>(js.size()));
  out.u32(0x4E4F534Au);  // "JSON"
  out.text(js.str());
  if (bin_chunk > 0) {
    out.u32(static_cast<std::uint32_t>(bin.size()));
    out.u32(0x004E4942u);  // "BIN\0"
    out.text(bin.str());
  }
  return out.str();
}

/// A glTF binary file with an empty scene and no BIN chunk: glTF allows no accessor with a
/// count of 0 nor an empty buffer, so a mesh without triangles has no mesh at all.
std::string empty_glb_bytes() {
  const nlohmann::json doc = {
      {"asset", {{"version", "2.0"}, {"generator", "zeroset"}}},
      {"scene", 0},
      {"scenes", nlohmann::json::array({{{"nodes", nlohmann::json::array()}}})}};
  return glb_container(doc, Bytes{});
}

std::string glb_bytes(const Mesh& m) {
  if (m.triangles.empty()) return empty_glb_bytes();
  const bool normals = has_normals(m);
  const size_t nv = m.positions.size(), nt = m.triangles.size();
  Bytes bin;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Vec3& p : m.positions)
    for (int k = 0; k < 3; ++k) {
      // min/max must match the stored floats exactly.
      const double f = static_cast<float>(p[k]);
      lo[k] = std::min(lo[k], f), hi[k] = std::max(hi[k], f);
      bin.f32(p[k]);
    }
  const size_t pos_bytes = bin.size();
  if (normals)
    for (const Vec3& n : m.normals)
      for (int k = 0; k < 3; ++k) bin.f32(n[k]);
  const size_t nrm_bytes = bin.size() - pos_bytes;
  for (const auto& t : m.triangles)
    for (std::uint32_t v : t) bin.u32(v);
  const size_t idx_bytes = bin.size() - pos_bytes - nrm_bytes;
  bin.pad(4, '\0');
  using nlohmann::json;
  json attributes = {{"POSITION", 0}};
  json views = json::array(
      {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", pos_bytes}, {"target", 34962}}});
  json accessors = json::array();
  json position = {{"bufferView", 0}, {"componentType", 5126}, {"count", nv}, {"type", "VEC3"}};
  if (nv > 0)
    position["min"] = {lo.x(), lo.y(), lo.z()}, position["max"] = {hi.x(), hi.y(), hi.z()};
  accessors.push_back(position);
  if (normals) {
    attributes["NORMAL"] = 1;
    views.push_back(
        {{"buffer", 0}, {"byteOffset", pos_bytes}, {"byteLength", nrm_bytes}, {"target", 34962}});
    accessors.push_back(
        {{"bufferView", 1}, {"componentType", 5126}, {"count", nv}, {"type", "VEC3"}});
  }
  const int index_view = normals ? 2 : 1;
  views.push_back({{"buffer", 0},
                   {"byteOffset", pos_bytes + nrm_bytes},
                   {"byteLength", idx_bytes},
                   {"target", 34963}});
  accessors.push_back(
      {{"bufferView", index_view}, {"componentType", 5125}, {"count", 3 * nt}, {"type", "SCALAR"}});
  const json doc = {
      {"asset", {{"version", "2.0"}, {"generator", "zeroset"}}},
      {"scene", 0},
      {"scenes", json::array({{{"nodes", json::array({0})}}})},
      {"nodes", json::array({{{"mesh", 0}}})},
      {"meshes", json::array({{{"primitives",
                                json::array({{{"attributes", attributes},
                                              {"indices", static_cast<int>(accessors.size()) - 1},
                                              {"mode", 4}}})}}})},
      {"buffers", json::array({{{"byteLength", bin.size()}}})},
      {"bufferViews", views},
      {"accessors", accessors},
  };
  return glb_container(doc, bin);
}

std::string known_list() {
  std::string s;
  for (const auto& e : mesh_file_extensions()) s += (s.empty() ? "." : ", .") + e;
  return s;
}

std::string checked_extension(const std::string& path) {
  const std::string ext = file_extension(path);
  const auto& known = mesh_file_extensions();
  if (std::find(known.begin(), known.end(), ext) == known.end())
    throw InvalidArgument(
        "output file", "'" + path + "'",
        (ext.empty() ? std::string("has no extension") : "unknown mesh format '." + ext + "'") +
            "; known formats: " + known_list());
  return ext;
}

// ---- reading -------------------------------------------------------------------------

class Reader {
 public:
  Reader(const std::string& path, std::string data) : path_(path), data_(std::move(data)) {}
  [[noreturn]] void fail(const std::string& why) const { throw IoError(path_, why); }
  size_t size() const { return data_.size(); }
  const std::string& data() const { return data_; }
  void need(size_t at, size_t n) const {
    if (at + n > data_.size() || at + n < at) fail("the file ends too early");
  }
  std::uint32_t u32(size_t at) const {
    need(at, 4);
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k)
      v |=
          static_cast<std::uint32_t>(static_cast<unsigned char>(data_[at + static_cast<size_t>(k)]))
          << (8 * k);
    return v;
  }
  std::uint16_t u16(size_t at) const {
    need(at, 2);
    return static_cast<std::uint16_t>(static_cast<unsigned char>(data_[at]) |
                                      (static_cast<unsigned char>(data_[at + 1]) << 8));
  }
  std::uint8_t u8(size_t at) const {
    need(at, 1);
    return static_cast<std::uint8_t>(data_[at]);
  }
  float f32(size_t at) const { return std::bit_cast<float>(u32(at)); }

 private:
  std::string path_;
  std::string data_;
};

void check_indices(const Reader& r, const Mesh& m) {
  for (const auto& t : m.triangles)
    for (std::uint32_t v : t)
      if (v >= m.positions.size())
        r.fail(fmt::format("a face refers to vertex {} of {}", v, m.positions.size()));
}

Mesh read_obj(const Reader& r) {
  Mesh m;
  std::istringstream in(r.data());
  std::string line;
  std::vector<Vec3> normals;
  int line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    std::istringstream ls(line);
    std::string tag;
    ls >> tag;
    if (tag == "v" || tag == "vn") {
      Vec3 p;
      if (!(ls >> p.x() >> p.y() >> p.z()))
        r.fail(fmt::format("line {}: expected three numbers", line_no));
      (tag == "v" ? m.positions : normals).push_back(p);
    } else if (tag == "f") {
      std::vector<std::uint32_t> idx;
      std::string tok;
      while (ls >> tok) {
        long long i = 0;
        try {
          i = std::stoll(tok.substr(0, tok.find('/')));
        } catch (const std::exception&) {
          r.fail(fmt::format("line {}: bad vertex index '{}'", line_no, tok));
        }
        if (i < 0) i += static_cast<long long>(m.positions.size()) + 1;
        if (i < 1) r.fail(fmt::format("line {}: bad vertex index '{}'", line_no, tok));
        idx.push_back(static_cast<std::uint32_t>(i - 1));
      }
      if (idx.size() < 3) r.fail(fmt::format("line {}: a face needs three vertices", line_no));
      for (size_t k = 1; k + 1 < idx.size(); ++k)
        m.triangles.push_back({idx[0], idx[k], idx[k + 1]});
    }
  }
  if (normals.size() == m.positions.size()) m.normals = std::move(normals);
  check_indices(r, m);
  return m;
}

Mesh read_ply_mesh(const std::string& path) {
  PlyData ply = read_ply(path);
  Mesh m;
  m.positions = std::move(ply.positions);
  m.normals = std::move(ply.normals);
  m.triangles = std::move(ply.triangles);
  if (const auto it = ply.properties.find("boundary"); it != ply.properties.end())
    for (double flag : it->second) m.is_boundary.push_back(flag != 0 ? 1 : 0);
  return m;
}

Mesh read_stl(const Reader& r) {
  if (r.size() < 84) r.fail("too short for a binary STL file");
  const std::uint32_t n = r.u32(80);
  if (r.size() != 84 + 50ull * n)
    r.fail("not a binary STL file (its size does not match its triangle count)");
  Mesh m;
  std::map<std::array<std::uint32_t, 3>, std::uint32_t> index;
  for (std::uint32_t t = 0; t < n; ++t) {
    std::array<std::uint32_t, 3> tri{};
    for (int c = 0; c < 3; ++c) {
      const size_t at = 84 + 50ull * t + 12 + 12ull * static_cast<size_t>(c);
      const std::array<std::uint32_t, 3> key = {r.u32(at), r.u32(at + 4), r.u32(at + 8)};
      auto [it, fresh] = index.try_emplace(key, static_cast<std::uint32_t>(m.positions.size()));
      if (fresh) m.positions.emplace_back(r.f32(at), r.f32(at + 4), r.f32(at + 8));
      tri[static_cast<size_t>(c)] = it->second;
    }
    m.triangles.push_back(tri);
  }
  return m;
}

Mesh read_glb(const Reader& r) {
  if (r.size() < 20 || r.u32(0) != 0x46546C67u) r.fail("not a glTF binary file");
  const std::uint32_t json_len = r.u32(12);
  if (r.u32(16) != 0x4E4F534Au) r.fail("the first chunk is not JSON");
  r.need(20, json_len);
  // The scene files' reader: nesting, size, repeated keys and NUL bytes are refused while the
  // chunk is parsed, before anything deep is built.
  nlohmann::json doc;
  try {
    doc = json_read::parse(std::string_view(r.data()).substr(20, json_len), "JSON chunk");
  } catch (const BadInput& e) {
    r.fail(e.what());
  }
  const size_t bin_at = 20 + json_len;
  // A file with no mesh (as an empty mesh is written) needs no BIN chunk.
  if (!doc.contains("meshes") || (doc["meshes"].is_array() && doc["meshes"].empty())) return Mesh{};
  const std::uint32_t bin_len = r.u32(bin_at);
  if (r.u32(bin_at + 4) != 0x004E4942u) r.fail("the second chunk is not BIN");
  r.need(bin_at + 8, bin_len);
  const size_t base = bin_at + 8;
  Mesh m;
  try {
    const auto& prim = doc.at("meshes").at(0).at("primitives").at(0);
    auto accessor = [&](int i, auto&& read_one) {
      const auto& acc = doc.at("accessors").at(static_cast<size_t>(i));
      const auto& view = doc.at("bufferViews").at(acc.at("bufferView").get<size_t>());
      const size_t off =
          base + view.value("byteOffset", size_t{0}) + acc.value("byteOffset", size_t{0});
      const size_t count = acc.at("count").get<size_t>();
      read_one(off, count, acc.at("componentType").get<int>());
    };
    accessor(prim.at("attributes").at("POSITION").get<int>(),
             [&](size_t off, size_t count, int type) {
               if (type != 5126) r.fail("positions must be floats");
               for (size_t v = 0; v < count; ++v)
                 m.positions.emplace_back(r.f32(off + 12 * v), r.f32(off + 12 * v + 4),
                                          r.f32(off + 12 * v + 8));
             });
    if (prim.at("attributes").contains("NORMAL"))
      accessor(prim.at("attributes").at("NORMAL").get<int>(), [&](size_t off, size_t count, int) {
        for (size_t v = 0; v < count; ++v)
          m.normals.emplace_back(r.f32(off + 12 * v), r.f32(off + 12 * v + 4),
                                 r.f32(off + 12 * v + 8));
      });
    accessor(prim.at("indices").get<int>(), [&](size_t off, size_t count, int type) {
      const size_t s = type == 5125 ? 4 : type == 5123 ? 2 : 1;
      std::vector<std::uint32_t> idx(count);
      for (size_t k = 0; k < count; ++k)
        idx[k] = s == 4 ? r.u32(off + 4 * k) : s == 2 ? r.u16(off + 2 * k) : r.u8(off + k);
      for (size_t k = 0; k + 2 < count; k += 3)
        m.triangles.push_back({idx[k], idx[k + 1], idx[k + 2]});
    });
  } catch (const nlohmann::json::exception& e) {
    r.fail(std::string("unexpected glTF structure: ") + e.what());
  }
  check_indices(r, m);
  return m;
}

}  // namespace

const std::vector<std::string>& mesh_file_extensions() {
  static const std::vector<std::string> known = {"obj", "ply", "stl", "glb"};
  return known;
}

void check_mesh_path(const std::string& path) {
  checked_extension(path);
  check_writable(path);
}

void write_mesh(const Mesh& mesh, const std::string& path) {
  const std::string ext = checked_extension(path);
  for (const auto& t : mesh.triangles)
    for (std::uint32_t v : t)
      if (v >= mesh.positions.size())
        throw InvalidArgument(
            "mesh", path,
            fmt::format("a triangle refers to vertex {} of {}", v, mesh.positions.size()));
  // Readers cannot parse nan or inf, and STL, glb and PLY hold floats: a mesh with a number
  // that is not finite or beyond a float's range is refused, not written.
  auto fits = [](const Vec3& p) {
    return (p.cwiseAbs().array() <= std::numeric_limits<float>::max()).all();
  };
  for (size_t v = 0; v < mesh.positions.size(); ++v)
    if (!fits(mesh.positions[v]) || (v < mesh.normals.size() && !fits(mesh.normals[v])))
      throw BadInput(
          fmt::format("{}: vertex {} of the mesh has a coordinate or normal that is "
                      "not finite or beyond a float's range; nothing written",
                      path, v));
  if (ext == "ply") {
    write_ply_mesh(mesh, path);
    return;
  }
  const std::string bytes = ext == "obj"   ? obj_bytes(mesh)
                            : ext == "stl" ? stl_bytes(mesh)
                                           : glb_bytes(mesh);
  write_file_atomically(path, [&](std::ostream& os) {
    os.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  });
}

Mesh read_mesh(const std::string& path) {
  const std::string ext = file_extension(path);
  const auto& known = mesh_file_extensions();
  if (std::find(known.begin(), known.end(), ext) == known.end())
    throw IoError(path, "unknown mesh format; known formats: " + known_list());
  if (ext == "ply") return read_ply_mesh(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot be opened");
  std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const Reader r(path, std::move(data));
  if (ext == "obj") return read_obj(r);
  if (ext == "stl") return read_stl(r);
  return read_glb(r);
}

}  // namespace zeroset
