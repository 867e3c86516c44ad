#include "semrec/usd/usda_writer.h"
#include "semrec/usd/usda_reader.h"

#include <cstdlib>
#include <fstream>
#include <optional>
#include <set>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/testing/test_util.h"
#include "semrec/usd/usd_test_util.h"

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

#define SEMREC_REQUIRE_VALIDATOR(var, file, dir)                      \
  const auto var = testing::ValidateUsd(file, dir);                   \
  if (!var)                                                           \
  SEMREC_SKIP(                                                        \
      "tinyusdz (npm) or node missing: run scripts/setup to install " \
      "it")

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

using test_scenes::Walker;

TEST(Usda, PeopleAreTimeSampledPrimsTheParserReads) {
  testing::TempDir dir;
  StageOptions options;
  options.time_codes_per_second = 10.0;
  options.end_time_code = 20.0;
  // Person 3 leaves after frame 4 and comes back at frame 9; person 8 enters
  // at frame 2.
  const std::vector<PersonTrack> people = {Walker(3, {0, 1, 2, 3, 4, 9, 10}),
                                           Walker(8, {2, 3})};
  WriteScene(dir.path(), {Tetrahedron("chair", 5, false)}, options, people);
  const std::string text = ReadTextFile(dir / "dynamic.usda");
  EXPECT_NE(text.find("timeCodesPerSecond = 10"), std::string::npos);
  EXPECT_NE(text.find("endTimeCode = 20"), std::string::npos);

  // Person 3: visible 0-4, invisible from 5, visible again at 9, invisible
  // after 10; person 8: invisible at 0, visible 2-3, invisible from 4.
  auto visibility_of = [&](const std::string& prim) {
    const size_t at = text.find("def Xform \"" + prim + "\"");
    const size_t from = text.find("visibility.timeSamples", at);
    return text.substr(from, text.find('}', from) - from);
  };
  const std::string v3 = visibility_of("person_3");
  EXPECT_NE(v3.find("5: \"invisible\""), std::string::npos) << v3;
  EXPECT_NE(v3.find("9: \"inherited\""), std::string::npos) << v3;
  EXPECT_NE(v3.find("11: \"invisible\""), std::string::npos) << v3;
  EXPECT_EQ(v3.find("0: \"invisible\""), std::string::npos) << v3;
  const std::string v8 = visibility_of("person_8");
  EXPECT_NE(v8.find("0: \"invisible\""), std::string::npos) << v8;
  EXPECT_NE(v8.find("2: \"inherited\""), std::string::npos) << v8;
  EXPECT_NE(v8.find("4: \"invisible\""), std::string::npos) << v8;
  // Points are stored relative to the translation.
  EXPECT_NE(text.find("9: (4.5, 1, 1)"), std::string::npos);
  EXPECT_NE(text.find("9: [(-0.25, 0, -1), (0.25, 0.125, 1)]"),
            std::string::npos);

  // Bad input: samples out of order, no frame rate, duplicates.
  PersonTrack backwards = Walker(1, {3, 2});
  EXPECT_THROW(DynamicLayerText({backwards}, options), InvalidArgument);
  EXPECT_THROW(DynamicLayerText({Walker(1, {0})}, StageOptions{}),
               InvalidArgument);
  EXPECT_THROW(DynamicLayerText({Walker(1, {0}), Walker(1, {1})}, options),
               InvalidArgument);
  EXPECT_NO_THROW(DynamicLayerText({}, StageOptions{}));

  // Our reader follows both sublayers and still finds the one mesh.
  EXPECT_EQ(ReadScene(dir / "scene.usda").size(), 1u);

  SEMREC_REQUIRE_VALIDATOR(result, dir / "dynamic.usda", dir.path());
  ASSERT_TRUE((*result)["ok"].get<bool>()) << (*result)["error"];
  const std::string layer = (*result)["layer"];
  // The parser's own serialisation: prims, samples and labels survived.
  for (const char* expected :
       {"def Xform \"person_3\"", "def Xform \"person_8\"",
        "def Points \"Cloud\"", "semrec:trackId = 8",
        "semantics:labels:class = [\"person\"]", "xformOp:translate"}) {
    EXPECT_NE(layer.find(expected), std::string::npos)
        << expected << " missing in\n"
        << layer;
  }
  const auto root = testing::ValidateUsd(dir / "scene.usda", dir.path());
  ASSERT_TRUE(root.has_value());
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

TEST(Usda, CustomLayerDataReadsBack) {
  testing::TempDir dir;
  StageOptions options;
  options.custom_layer_data = {
      {"T_upright_world", "1 0 0 0 0 0 -1 0.5 0 1 0 0 0 0 0 1"},
      {"input", "C:\\data \"tilted\" (semrec layout)"}};
  WriteScene(dir.path(), {Tetrahedron("chair", 5, false)}, options);
  // Every layer carries it: the root and the layer with the meshes.
  for (const char* layer : {"scene.usda", "static.usda", "dynamic.usda"}) {
    EXPECT_EQ(ReadCustomLayerData(dir / layer), options.custom_layer_data)
        << layer;
  }
  testing::TempDir plain;
  WriteScene(plain.path(), {}, {});
  EXPECT_TRUE(ReadCustomLayerData(plain / "static.usda").empty());
  // Other tools' layers: typed values as written, nested dictionaries skipped.
  testing::WriteText(dir / "other.usda",
                     "#usda 1.0\n\n(\n    customLayerData = {\n"
                     "        double scale = 2.5\n"
                     "        dictionary nested = {\n"
                     "            string inner = \"x\"\n        }\n"
                     "        string after = \"y\"\n    }\n)\n"
                     "def Xform \"World\" {}\n");
  const std::map<std::string, std::string> other =
      ReadCustomLayerData(dir / "other.usda");
  EXPECT_EQ(other, (std::map<std::string, std::string>{{"after", "y"},
                                                       {"scale", "2.5"}}));
  testing::WriteText(dir / "none.usda", "#usda 1.0\ndef Xform \"World\" {}\n");
  EXPECT_TRUE(ReadCustomLayerData(dir / "none.usda").empty());

  testing::WriteText(dir / "x.usda", "hello");
  EXPECT_THROW(ReadCustomLayerData(dir / "x.usda"), FormatError);
  testing::WriteText(dir / "open.usda",
                     "#usda 1.0\n(\n    customLayerData = {\n");
  EXPECT_THROW(ReadCustomLayerData(dir / "open.usda"), FormatError);
  testing::WriteText(dir / "bad.usda",
                     "#usda 1.0\n(\n    customLayerData = {\n        junk\n"
                     "    }\n)\n");
  try {
    ReadCustomLayerData(dir / "bad.usda");
    ADD_FAILURE() << "no error";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.usda: line 4: bad "
                                         "customLayerData entry 'junk'"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ReadCustomLayerData(dir / "missing.usda"), IoError);
}

}  // namespace
}  // namespace semrec::usd
