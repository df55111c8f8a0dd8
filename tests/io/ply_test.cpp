// PLY files as plain arrays: exact bytes, round trips in both formats, faces, and errors.
#include "zeroset/io/ply.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <limits>
#include <vector>

#include "zeroset/error.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;

class IoPlyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("zeroset_io_ply_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::string write_text(const std::string& name, const std::string& text) const {
    std::ofstream(path(name), std::ios::binary) << text;
    return path(name);
  }
  std::string read_bytes(const std::string& name) const {
    std::ifstream in(path(name), std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
  }

  fs::path dir_;
  const std::vector<Vec3> positions_ = {Vec3(1, 2, 3), Vec3(-0.5, 0.25, 1e-3), Vec3(0, 0, 0),
                                        Vec3(0, 1, 0)};
  const std::vector<Vec3> normals_ = {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0, -1, 0), Vec3(0, 0, -1)};
  const std::vector<double> flags_ = {1, 0, 0, 1};
  const std::vector<double> radii_ = {0.1, 0.2, 0.05, 0.3};
  const std::vector<std::array<std::uint32_t, 3>> triangles_ = {{0, 1, 2}, {0, 2, 3}};

  PlyContent mesh_content() const {
    PlyContent c;
    c.comment = "test";
    c.positions = positions_;
    c.normals = normals_;
    c.properties = {{"radius", PlyScalar::kFloat, radii_}, {"boundary", PlyScalar::kUChar, flags_}};
    c.has_faces = true;
    c.triangles = triangles_;
    return c;
  }
};

void expect_close(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LT((a[i] - b[i]).norm(), 1e-6);
}

TEST_F(IoPlyTest, BinaryHeaderAndRecordSizes) {
  write_ply(path("a.ply"), mesh_content());
  const std::string bytes = read_bytes("a.ply");
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment test\nelement vertex 4\n"
      "property float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "property float radius\nproperty uchar boundary\n"
      "element face 2\nproperty list uchar uint vertex_indices\nend_header\n";
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  // 4 vertices × (7 floats + 1 byte), 2 faces × (1 + 3 × 4) bytes.
  EXPECT_EQ(bytes.size() - header.size(), 4u * 29u + 2u * 13u);
}

TEST_F(IoPlyTest, RoundTripInBothFormats) {
  for (PlyFormat format : {PlyFormat::kBinaryLittleEndian, PlyFormat::kAscii}) {
    write_ply(path("b.ply"), mesh_content(), format);
    const PlyData ply = read_ply(path("b.ply"));
    expect_close(ply.positions, positions_);
    expect_close(ply.normals, normals_);
    ASSERT_EQ(ply.properties.size(), 2u);
    EXPECT_EQ(ply.properties.at("boundary"), flags_);
    ASSERT_EQ(ply.properties.at("radius").size(), 4u);
    EXPECT_NEAR(ply.properties.at("radius")[1], 0.2, 1e-7);
    EXPECT_TRUE(ply.has_faces);
    EXPECT_EQ(ply.triangles, triangles_);
  }
}

// Every number is written as a float: one that is not finite or beyond a float's range would
// become a word no reader parses, so the file is refused and nothing is written.
TEST_F(IoPlyTest, NumbersThatAreNotFiniteFloatsAreRefused) {
  for (double bad :
       {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), 1e39}) {
    for (int where = 0; where < 3; ++where) {
      PlyContent c = mesh_content();
      std::vector<Vec3> positions = positions_, normals = normals_;
      std::vector<double> radius(positions_.size(), 0.1);
      if (where == 0) positions[1].y() = bad;
      if (where == 1) normals[2].z() = bad;
      if (where == 2) radius[3] = bad;
      c.positions = positions;
      c.normals = normals;
      c.properties = {{"radius", PlyScalar::kFloat, radius}};
      EXPECT_THROW(write_ply(path("bad.ply"), c, PlyFormat::kAscii), BadInput);
      EXPECT_FALSE(fs::exists(path("bad.ply")));
    }
  }
}

TEST_F(IoPlyTest, PointsWithoutFacesOrNormals) {
  PlyContent c;
  c.positions = positions_;
  write_ply(path("c.ply"), c, PlyFormat::kAscii);
  EXPECT_EQ(read_bytes("c.ply").find("comment"), std::string::npos);
  const PlyData ply = read_ply(path("c.ply"));
  expect_close(ply.positions, positions_);
  EXPECT_TRUE(ply.normals.empty());
  EXPECT_TRUE(ply.properties.empty());
  EXPECT_FALSE(ply.has_faces);
}

TEST_F(IoPlyTest, ReadsPolygonsOtherTypesAndSkippedFaceProperties) {
  const PlyData ply = read_ply(write_text(
      "d.ply",
      "ply\r\nformat ascii 1.0\r\nobj_info x\r\nelement vertex 4\r\nproperty double x\r\n"
      "property int y\r\nproperty uchar z\r\nelement face 1\r\nproperty uchar flag\r\n"
      "property list ushort int vertex_index\r\nend_header\r\n"
      "0 0 0\r\n1.5 -2 3\r\n1 1 0\r\n0 1 0\r\n7 4 0 1 2 3\r\n"));
  expect_close(ply.positions, {Vec3(0, 0, 0), Vec3(1.5, -2, 3), Vec3(1, 1, 0), Vec3(0, 1, 0)});
  EXPECT_EQ(ply.triangles, (std::vector<std::array<std::uint32_t, 3>>{{0, 1, 2}, {0, 2, 3}}));
}

TEST_F(IoPlyTest, EdgesRoundTripWithTheirKindAndAreCheckedOnReading) {
  const std::vector<std::array<std::uint32_t, 2>> edges = {{0, 1}, {1, 3}};
  const std::vector<std::uint8_t> kinds = {0, 1};
  for (PlyFormat format : {PlyFormat::kBinaryLittleEndian, PlyFormat::kAscii}) {
    PlyContent c = mesh_content();
    c.edges = edges;
    c.edge_kinds = kinds;
    write_ply(path("e.ply"), c, format);
    const PlyData ply = read_ply(path("e.ply"));
    EXPECT_EQ(ply.edges, edges);
    EXPECT_EQ(ply.triangles, triangles_);
  }
  PlyContent bad = mesh_content();
  const std::vector<std::array<std::uint32_t, 2>> out_of_range = {{0, 9}};
  bad.edges = out_of_range;
  EXPECT_THROW(write_ply(path("f.ply"), bad), InvalidArgument);
  EXPECT_THROW(read_ply(write_text("g.ply",
                                   "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                   "property float y\nproperty float z\nelement edge 1\n"
                                   "property int vertex1\nproperty int vertex2\nend_header\n"
                                   "0 0 0\n0 5\n")),
               IoError);
}

TEST_F(IoPlyTest, WritingRejectsMismatchesBeforeWriting) {
  PlyContent c = mesh_content();
  c.normals = std::span<const Vec3>(normals_.data(), 2);
  EXPECT_THROW(write_ply(path("e.ply"), c), InvalidArgument);
  c = mesh_content();
  c.properties[0].values = std::span<const double>(radii_.data(), 1);
  EXPECT_THROW(write_ply(path("e.ply"), c), InvalidArgument);
  c = mesh_content();
  const std::vector<std::array<std::uint32_t, 3>> bad = {{0, 1, 4}};
  c.triangles = bad;
  EXPECT_THROW(write_ply(path("e.ply"), c), InvalidArgument);
  EXPECT_FALSE(fs::exists(path("e.ply")));
}

TEST_F(IoPlyTest, UnwritablePathThrowsIoErrorNamingIt) {
  const std::string bad = path("missing/dir/f.ply");
  try {
    write_ply(bad, mesh_content());
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_EQ(e.path(), bad);
  }
}

TEST_F(IoPlyTest, ReadingRejectsBrokenFiles) {
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n";
  const std::string xyz = head + "property float y\nproperty float z\n";
  EXPECT_THROW(read_ply(path("missing.ply")), IoError);
  EXPECT_THROW(read_ply(write_text("g1.ply", "solid stl\n")), IoError);
  EXPECT_THROW(read_ply(write_text("g2.ply", xyz)), IoError);  // no end_header
  EXPECT_THROW(read_ply(write_text("g3.ply", xyz + "end_header\n1 2 3\n")), IoError);  // short
  EXPECT_THROW(read_ply(write_text("g4.ply", head + "end_header\n1\n2\n")), IoError);  // no y, z
  EXPECT_THROW(read_ply(write_text("g5.ply", "ply\nformat binary_big_endian 1.0\nend_header\n")),
               IoError);
  EXPECT_THROW(read_ply(write_text("g6.ply", xyz + "element edge 1\nproperty int a\nend_header\n"
                                                   "0 0 0\n1 1 1\n0\n")),
               IoError);
  EXPECT_THROW(read_ply(write_text("g7.ply", xyz + "element face 1\n"
                                                   "property list uchar int vertex_indices\n"
                                                   "end_header\n0 0 0\n1 1 1\n3 0 1 2\n")),
               IoError);  // vertex 2 of 2
  // Binary, cut inside the second vertex.
  PlyContent c;
  c.positions = positions_;
  write_ply(path("g8.ply"), c);
  const std::string bytes = read_bytes("g8.ply");
  EXPECT_THROW(read_ply(write_text("g8.ply", bytes.substr(0, bytes.size() - 30))), IoError);
}

}  // namespace
}  // namespace zeroset
