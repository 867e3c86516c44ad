#include "semrec/io/ply_io.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace semrec::io {
namespace {

TEST(PlyIo, RoundTripPointsColorsLabelsTriangles) {
  semrec::testing::TempDir dir;
  PlyData data;
  data.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0.5f}};
  data.colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}};
  data.labels = {7, 8, 70000};
  data.triangles = {{0, 1, 2}};
  WritePly(dir / "a.ply", data);
  const PlyData back = ReadPly(dir / "a.ply");
  EXPECT_EQ(back.points, data.points);
  EXPECT_EQ(back.colors, data.colors);
  EXPECT_EQ(back.labels, data.labels);
  EXPECT_EQ(back.triangles, data.triangles);
}

TEST(PlyIo, ReadsAsciiWithDoublesAndQuads) {
  semrec::testing::TempDir dir;
  semrec::testing::WriteText(
      dir / "q.ply",
      "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n"
      "property double y\nproperty double z\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  const PlyData q = ReadPly(dir / "q.ply");
  ASSERT_EQ(q.points.size(), 4u);
  ASSERT_EQ(q.triangles.size(), 2u);  // the quad is fan-triangulated
  EXPECT_EQ(q.triangles[1], (std::array<uint32_t, 3>{0, 2, 3}));
}

TEST(PlyIo, Errors) {
  semrec::testing::TempDir dir;
  PlyData bad;
  bad.points = {{0, 0, 0}};
  bad.triangles = {{0, 1, 2}};
  EXPECT_THROW(WritePly(dir / "b.ply", bad), InvalidArgument);
  semrec::testing::WriteText(
      dir / "t.ply",
      "ply\nformat binary_little_endian 1.0\nelement vertex 10\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n"
      "short");
  EXPECT_THROW(ReadPly(dir / "t.ply"), FormatError);
  semrec::testing::WriteText(dir / "n.ply", "hello");
  EXPECT_THROW(ReadPly(dir / "n.ply"), FormatError);
}

}  // namespace
}  // namespace semrec::io

namespace semrec::io {
namespace {

TEST(Ply, NamedIntegerPropertiesRoundTrip) {
  semrec::testing::TempDir dir;
  PlyData data;
  data.points = {{0, 0, 0}, {1, 2, 3}};
  data.labels = {7, 8};
  data.int_properties = {{"semantic", {4, -1}}, {"instance", {12, 0}}};
  WritePly(dir / "gt.ply", data);
  const PlyData back = ReadPly(dir / "gt.ply");
  EXPECT_EQ(back.labels, data.labels);
  ASSERT_EQ(back.int_properties.size(), 2u);
  EXPECT_EQ(back.int_properties[0].first, "semantic");
  EXPECT_EQ(back.int_properties[0].second, (std::vector<int32_t>{4, -1}));
  EXPECT_EQ(back.int_properties[1].first, "instance");
  EXPECT_EQ(back.int_properties[1].second, (std::vector<int32_t>{12, 0}));
  // ASCII files with other types work too.
  semrec::testing::WriteText(dir / "a.ply",
                             "ply\nformat ascii 1.0\nelement vertex 1\n"
                             "property float x\nproperty float y\n"
                             "property float z\nproperty ushort semantic\n"
                             "end_header\n1 2 3 5\n");
  const PlyData a = ReadPly(dir / "a.ply");
  ASSERT_EQ(a.int_properties.size(), 1u);
  EXPECT_EQ(a.int_properties[0].second, (std::vector<int32_t>{5}));
  data.int_properties[1].second.pop_back();
  EXPECT_THROW(WritePly(dir / "bad.ply", data), InvalidArgument);
}

}  // namespace
}  // namespace semrec::io
