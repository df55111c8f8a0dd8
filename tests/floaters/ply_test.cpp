// Point-set PLY files: round trips, and errors that leave nothing behind.
#include "zeroset/floaters/ply.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "zeroset/error.h"

namespace zeroset {
namespace {

namespace fs = std::filesystem;

class PlyTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("zeroset_ply_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  fs::path dir_;
  const std::vector<Vec3> positions_ = {Vec3(1, 2, 3), Vec3(-0.5, 0.25, 1e-3), Vec3(0, 0, 0)};
  const std::vector<Vec3> normals_ = {Vec3(0, 0, 1), Vec3(1, 0, 0), Vec3(0, -1, 0)};
  const std::vector<double> radii_ = {0.1, 0.2, 0.05};
};

void expect_close(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_LT((a[i] - b[i]).norm(), 1e-6);
}

TEST_F(PlyTest, BinaryRoundTrip) {
  write_points_ply(path("a.ply"), positions_, normals_, radii_);
  const PointSet ps = read_points_ply(path("a.ply"));
  expect_close(ps.positions, positions_);
  expect_close(ps.normals, normals_);
  ASSERT_EQ(ps.radii.size(), 3u);
  EXPECT_NEAR(ps.radii[1], 0.2, 1e-7);
  // 3 points × 7 floats after the header.
  std::ifstream in(path("a.ply"), std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(text.find("format binary_little_endian 1.0"), std::string::npos);
  EXPECT_EQ(text.size() - (text.find("end_header\n") + 11), 3u * 7u * 4u);
}

TEST_F(PlyTest, AsciiRoundTripWithoutOptionalProperties) {
  write_points_ply(path("b.ply"), positions_, {}, {}, PlyFormat::kAscii);
  const PointSet ps = read_points_ply(path("b.ply"));
  expect_close(ps.positions, positions_);
  EXPECT_TRUE(ps.normals.empty());
  EXPECT_TRUE(ps.radii.empty());
}

TEST_F(PlyTest, EmptyPointSet) {
  write_points_ply(path("c.ply"), {}, {}, {});
  EXPECT_TRUE(read_points_ply(path("c.ply")).positions.empty());
}

TEST_F(PlyTest, MismatchedSizesAreRejectedBeforeWriting) {
  EXPECT_THROW(write_points_ply(path("d.ply"), positions_, {normals_.data(), 2}), InvalidArgument);
  EXPECT_THROW(write_points_ply(path("d.ply"), positions_, {}, {radii_.data(), 1}),
               InvalidArgument);
  EXPECT_FALSE(fs::exists(path("d.ply")));
}

TEST_F(PlyTest, UnwritablePathThrowsIoErrorNamingIt) {
  const std::string bad = path("missing/dir/e.ply");
  try {
    write_points_ply(bad, positions_);
    FAIL() << "no exception";
  } catch (const IoError& e) {
    EXPECT_EQ(e.path(), bad);
  }
}

TEST_F(PlyTest, ReadingRejectsWhatIsNotAPointSet) {
  EXPECT_THROW(read_points_ply(path("nothing.ply")), IoError);
  {
    std::ofstream out(path("f.ply"));
    out << "solid stl\n";
  }
  EXPECT_THROW(read_points_ply(path("f.ply")), IoError);
  {
    std::ofstream out(path("g.ply"));
    out << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
           "property float z\nend_header\n1 2 3\n";
  }
  EXPECT_THROW(read_points_ply(path("g.ply")), IoError);  // truncated
  {
    std::ofstream out(path("h.ply"));
    out << "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n";
  }
  EXPECT_THROW(read_points_ply(path("h.ply")), IoError);  // no y, z
}

}  // namespace
}  // namespace zeroset
