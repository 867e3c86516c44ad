#include "semrec/usd/usda_writer.h"

#include <cstdlib>
#include <fstream>
#include <optional>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec::usd {
namespace {

MeshPrim Tetrahedron(const std::string& label, uint32_t id, bool per_vertex) {
  MeshPrim m;
  m.label = label;
  m.instance_id = id;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1.5f}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}};
  if (per_vertex) {
    m.normals = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    m.vertex_colors = {{255, 0, 0}, {0, 255, 0}, {0, 0, 255}, {10, 20, 30}};
  }
  m.point_count = 1234;
  m.first_seen_frame = 2;
  m.last_seen_frame = 9;
  return m;
}

#define SEMREC_REQUIRE_VALIDATOR(var, file, dir)    \
  const auto var = testing::ValidateUsd(file, dir); \
  if (!var)                                         \
  GTEST_SKIP()                                      \
      << "tinyusdz (npm) or node missing: run scripts/setup to install it"

TEST(Usda, IndependentParserReadsWhatWeWrite) {
  testing::TempDir dir;
  StageOptions options;
  options.custom_layer_data = {{"input", "synthetic \"six-objects\""},
                               {"alpha", "0.5"}};
  const std::vector<MeshPrim> meshes = {
      Tetrahedron("chair", 5, true), Tetrahedron("potted plant/2", 7, false)};
  WriteScene(dir.path(), meshes, options);
  SEMREC_REQUIRE_VALIDATOR(result, dir / "static.usda", dir.path());
  ASSERT_TRUE((*result)["ok"].get<bool>()) << (*result)["error"];
  ASSERT_EQ((*result)["meshes"].size(), 2u);
  for (const auto& m : (*result)["meshes"]) {
    EXPECT_EQ(m["points"].get<int>(), 4);
    EXPECT_EQ(m["faceVertexIndices"].get<int>(), 12);
    EXPECT_EQ(m["faceVertexCounts"], nlohmann::json::array({3, 3, 3, 3}));
  }
  std::set<std::string> paths;
  for (const auto& m : (*result)["meshes"])
    paths.insert(m["path"].get<std::string>());
  EXPECT_EQ(paths, (std::set<std::string>{"/World/Objects/chair_5",
                                          "/World/Objects/potted_plant_2_7"}));
  const std::string layer = (*result)["layer"];
  EXPECT_NE(layer.find("upAxis = \"Z\""), std::string::npos) << layer;
  EXPECT_NE(layer.find("token[] semantics:labels:class = [\"chair\"]"),
            std::string::npos)
      << layer;
  EXPECT_NE(layer.find("semantics:labels:class = [\"potted plant/2\"]"),
            std::string::npos);
  EXPECT_NE(layer.find("potted_plant_2_7"), std::string::npos)
      << "sanitised prim name";
  EXPECT_NE(layer.find("semantic:Semantics:params:semanticData = \"chair\""),
            std::string::npos);
  EXPECT_NE(layer.find("semrec:instanceId = 7"), std::string::npos);
  EXPECT_NE(layer.find("semrec:pointCount = 1234"), std::string::npos);

  SEMREC_REQUIRE_VALIDATOR(root, dir / "scene.usda", dir.path());
  EXPECT_TRUE((*root)["ok"].get<bool>()) << (*root)["error"];
}

// The validator must bite: a truncated file and a misspelt type are rejected.
TEST(Usda, IndependentParserRejectsBrokenFiles) {
  testing::TempDir dir;
  const std::string text = StaticLayerText({Tetrahedron("chair", 1, true)}, {});
  testing::WriteText(dir / "truncated.usda", text.substr(0, text.size() / 2));
  SEMREC_REQUIRE_VALIDATOR(truncated, dir / "truncated.usda", dir.path());
  EXPECT_FALSE((*truncated)["ok"].get<bool>());
  std::string misspelt = text;
  misspelt.replace(misspelt.find("point3f[]"), 9, "pointz3f[]");
  testing::WriteText(dir / "misspelt.usda", misspelt);
  SEMREC_REQUIRE_VALIDATOR(bad_type, dir / "misspelt.usda", dir.path());
  EXPECT_FALSE((*bad_type)["ok"].get<bool>());
}

TEST(Usda, NamesAndErrors) {
  EXPECT_EQ(SanitizeName("chair"), "chair");
  EXPECT_EQ(SanitizeName("potted plant/2"), "potted_plant_2");
  EXPECT_EQ(SanitizeName("3d-box"), "_3d_box");
  EXPECT_EQ(SanitizeName(""), "_");
  MeshPrim bad = Tetrahedron("x", 1, false);
  bad.triangles.push_back({0, 1, 9});
  EXPECT_THROW(StaticLayerText({bad}, {}), InvalidArgument);
  EXPECT_THROW(
      StaticLayerText({Tetrahedron("a", 1, false), Tetrahedron("a", 1, false)},
                      {}),
      InvalidArgument);
  StageOptions y;
  y.up_axis = "X";
  EXPECT_THROW(y.Check(), InvalidArgument);
  EXPECT_THROW(WriteScene("/proc/forbidden", {}, {}), Error);
}

}  // namespace
}  // namespace semrec::usd

#include "semrec/usd/usda_reader.h"

namespace semrec::usd {
namespace {

TEST(Usda, RoundTripThroughOurReader) {
  testing::TempDir dir;
  const std::vector<MeshPrim> meshes = {
      Tetrahedron("chair", 5, true), Tetrahedron("potted \"plant\"", 7, false)};
  WriteScene(dir.path(), meshes, {});
  const std::vector<MeshPrim> back =
      ReadScene(dir / "scene.usda");  // follows subLayers
  ASSERT_EQ(back.size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(back[i].label, meshes[i].label);
    EXPECT_EQ(back[i].instance_id, meshes[i].instance_id);
    EXPECT_EQ(back[i].points, meshes[i].points);
    EXPECT_EQ(back[i].triangles, meshes[i].triangles);
    EXPECT_EQ(back[i].point_count, 1234u);
    EXPECT_EQ(back[i].last_seen_frame, 9u);
  }
  testing::WriteText(dir / "x.usda", "hello");
  EXPECT_THROW(ReadScene(dir / "x.usda"), FormatError);
}

}  // namespace
}  // namespace semrec::usd
