#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <fstream>

#include "mesh_test_support.h"
#include "zeroset/error.h"
#include "zeroset/mesh/mesh_io.h"
#include "zeroset/mesh/polygonize.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;

class MeshIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("zeroset_mesh_io_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  fs::path dir_;
};

TEST_F(MeshIo, RoundTripsEveryFormat) {
  const Surface s = test::catalog_surface("torus");
  const Mesh m = polygonize(s, {.cells = 24});
  ASSERT_FALSE(m.empty());
  for (const std::string& ext : mesh_file_extensions()) {
    const std::string p = path("torus." + ext);
    write_mesh(m, p);
    const Mesh r = read_mesh(p);
    EXPECT_EQ(r.triangle_count(), m.triangle_count()) << ext;
    EXPECT_EQ(r.vertex_count(), m.vertex_count()) << ext;
    ASSERT_EQ(r.triangles.size(), m.triangles.size());
    if (ext != "stl") {  // STL renumbers its vertices
      EXPECT_EQ(r.triangles.front(), m.triangles.front()) << ext;
      for (size_t v = 0; v < m.positions.size(); v += 97)
        EXPECT_LT((r.positions[v] - m.positions[v]).norm(), 1e-6) << ext;
      EXPECT_EQ(r.normals.size(), m.normals.size()) << ext;
    }
  }
  EXPECT_EQ(read_mesh(path("torus.ply")).is_boundary, m.is_boundary);
}

// A mesh without triangles (a surface that misses the clip) is a valid glTF file of an empty
// scene: no accessor with a count of 0, no empty buffer, no BIN chunk; it reads back empty.
TEST_F(MeshIo, AnEmptyMeshIsAValidGlbOfAnEmptyScene) {
  const std::string p = path("empty.glb");
  write_mesh(Mesh{}, p);
  std::ifstream in(p, std::ios::binary);
  const std::string bytes{std::istreambuf_iterator<char>(in), {}};
  ASSERT_GE(bytes.size(), 20u);
  EXPECT_EQ(bytes.substr(0, 4), "glTF");
  std::uint32_t total = 0, json_len = 0;
  std::memcpy(&total, bytes.data() + 8, 4);
  std::memcpy(&json_len, bytes.data() + 12, 4);
  EXPECT_EQ(total, bytes.size());
  EXPECT_EQ(20 + json_len, bytes.size()) << "a JSON chunk and nothing else";
  const auto doc = nlohmann::json::parse(bytes.substr(20, json_len));
  EXPECT_EQ(doc["asset"]["version"], "2.0");
  EXPECT_FALSE(doc.contains("accessors"));
  EXPECT_FALSE(doc.contains("buffers"));
  EXPECT_TRUE(doc["scenes"][0]["nodes"].empty());
  const Mesh r = read_mesh(p);
  EXPECT_TRUE(r.positions.empty());
  EXPECT_TRUE(r.triangles.empty());
}

TEST_F(MeshIo, RejectsUnknownExtensionListingKnownOnes) {
  Mesh m;
  try {
    write_mesh(m, path("mesh.xyz"));
    FAIL();
  } catch (const InvalidArgument& e) {
    const std::string what = e.what();
    for (const char* ext : {".obj", ".ply", ".stl", ".glb"})
      EXPECT_NE(what.find(ext), std::string::npos);
  }
  EXPECT_FALSE(fs::exists(path("mesh.xyz")));
  EXPECT_THROW(check_mesh_path(path("noext")), InvalidArgument);
}

TEST_F(MeshIo, RejectsUnwritablePathWithoutPartialFile) {
  const Mesh m = polygonize(test::catalog_surface("sphere"), {.cells = 8});
  const std::string bad = path("missing/dir/mesh.obj");
  EXPECT_THROW(write_mesh(m, bad), IoError);
  EXPECT_THROW(check_mesh_path(bad), IoError);
  EXPECT_FALSE(fs::exists(bad));
}

TEST_F(MeshIo, ReadingABrokenFileIsAnIoError) {
  std::ofstream(path("broken.ply")) << "ply\nformat ascii 1.0\nend_header\n";
  EXPECT_THROW(read_mesh(path("broken.ply")), IoError);
  std::ofstream(path("short.stl")) << "solid";
  EXPECT_THROW(read_mesh(path("short.stl")), IoError);
  std::ofstream(path("bad.obj")) << "v 0 0 0\nf 1 2 3\n";
  EXPECT_THROW(read_mesh(path("bad.obj")), IoError);
}

// A glTF binary's JSON chunk is read like a scene file: 10^5 levels of nesting are refused
// while parsing (no deep recursion, no crash), and so is a repeated key, naming the file.
TEST_F(MeshIo, GlbJsonChunkIsReadWithTheSceneFilesLimits) {
  auto glb = [&](const std::string& name, std::string json) {
    while (json.size() % 4 != 0) json += ' ';
    std::string bytes;
    auto u32 = [&](std::uint32_t v) {
      for (int k = 0; k < 4; ++k) bytes += static_cast<char>((v >> (8 * k)) & 0xFFu);
    };
    u32(0x46546C67u);
    u32(2);
    u32(static_cast<std::uint32_t>(12 + 8 + json.size() + 8));
    u32(static_cast<std::uint32_t>(json.size()));
    u32(0x4E4F534Au);
    bytes += json;
    u32(0);
    u32(0x004E4942u);
    std::ofstream(path(name), std::ios::binary) << bytes;
    return path(name);
  };
  const std::string deep =
      glb("deep.glb", "{\"extras\":" + std::string(100000, '[') + std::string(100000, ']') + "}");
  try {
    read_mesh(deep);
    FAIL() << "deep JSON accepted";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("deep.glb"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nest"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_mesh(glb("twice.glb", R"({"meshes": [], "meshes": []})")), IoError);
}

}  // namespace
}  // namespace zeroset
