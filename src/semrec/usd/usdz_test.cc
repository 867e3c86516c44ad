#include "semrec/usd/usdz.h"

#include <cstdlib>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "semrec/core/error.h"
#include "semrec/core/file_util.h"
#include "semrec/testing/test_util.h"
#include "semrec/usd/usda_writer.h"

namespace semrec::usd {
namespace {

TEST(Usdz, Crc32MatchesTheStandardCheckValue) {
  EXPECT_EQ(Crc32("123456789"), 0xCBF43926u);
  EXPECT_EQ(Crc32(""), 0u);
}

MeshPrim Triangle(const std::string& label, uint32_t id) {
  MeshPrim m;
  m.label = label;
  m.instance_id = id;
  m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}};
  return m;
}

// Python's zipfile (independent of our writer) reads the archive: stored
// entries, correct CRCs, the layers in order, every payload 64-byte aligned.
TEST(Usdz, ZipReadersSeeAlignedStoredLayers) {
  testing::TempDir dir;
  WriteScene(dir.path(), {Triangle("chair", 1), Triangle("table", 2)}, {});
  std::vector<std::pair<std::string, std::string>> files;
  for (const char* name : {"scene.usda", "dynamic.usda", "static.usda"})
    files.emplace_back(name, ReadTextFile(dir / name));
  // An odd-sized binary member to exercise the padding.
  files.emplace_back("textures/x.bin", std::string("\0\x01\x02\xff\x80", 5));
  WriteUsdz(dir / "scene.usdz", files);

  testing::WriteText(dir / "check.py", R"py(
import json, struct, sys, zipfile
path = sys.argv[1]
raw = open(path, 'rb').read()
z = zipfile.ZipFile(path)
out = {'names': z.namelist(), 'bad': z.testzip(), 'stored': True, 'aligned': True}
for info in z.infolist():
    out['stored'] &= info.compress_type == zipfile.ZIP_STORED
    n, e = struct.unpack('<HH', raw[info.header_offset + 26:info.header_offset + 30])
    out['aligned'] &= (info.header_offset + 30 + n + e) % 64 == 0
out['static'] = z.read('static.usda').decode()
print(json.dumps(out))
)py");
  const std::string cmd = "/usr/bin/python3 '" + (dir / "check.py").string() +
                          "' '" + (dir / "scene.usdz").string() + "' > '" +
                          (dir / "check.json").string() + "'";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const auto check = nlohmann::json::parse(ReadTextFile(dir / "check.json"));
  EXPECT_EQ(check["names"],
            nlohmann::json::array({"scene.usda", "dynamic.usda", "static.usda",
                                   "textures/x.bin"}));
  EXPECT_TRUE(check["bad"].is_null()) << check["bad"];
  EXPECT_TRUE(check["stored"].get<bool>());
  EXPECT_TRUE(check["aligned"].get<bool>());
  EXPECT_EQ(check["static"].get<std::string>(), files[2].second);

  // Bad input.
  EXPECT_THROW(UsdzBytes({}), InvalidArgument);
  EXPECT_THROW(UsdzBytes({{"x.png", "a"}}), InvalidArgument);
  EXPECT_THROW(UsdzBytes({{"a.usda", "a"}, {"a.usda", "b"}}), InvalidArgument);
  EXPECT_THROW(UsdzBytes({{"a.usda", "a"}, {"../b.usda", "b"}}),
               InvalidArgument);
  EXPECT_THROW(UsdzBytes({{"/abs.usda", "a"}}), InvalidArgument);
}

// The independent USD parser opens the package: objects and people in one
// flattened layer.
TEST(Usdz, TinyusdzLoadsTheScenePackage) {
  testing::TempDir dir;
  PersonTrack person;
  person.track_id = 4;
  for (size_t f : {0, 1, 5}) {
    PersonSample s;
    s.frame = f;
    s.centroid_world = {static_cast<float>(f), 0, 1};
    s.points_world = {{static_cast<float>(f), 0, 0},
                      {static_cast<float>(f), 0, 2}};
    person.samples.push_back(s);
  }
  StageOptions options;
  options.time_codes_per_second = 10;
  options.end_time_code = 5;
  WriteSceneUsdz(dir / "scene.usdz",
                 {Triangle("chair", 1), Triangle("table", 2)}, options,
                 {person});
  const auto result = testing::ValidateUsd(dir / "scene.usdz", dir.path());
  if (!result) SEMREC_SKIP("tinyusdz (npm) or node missing");
  ASSERT_TRUE((*result)["ok"].get<bool>()) << (*result)["error"];
  EXPECT_EQ((*result)["meshes"].size(), 2u);
  // The validator bites: a truncated package is refused.
  const std::string flat = FlatLayerText({Triangle("chair", 1)}, {}, {});
  const std::string bytes = ReadTextFile(dir / "scene.usdz");
  testing::WriteText(dir / "broken.usdz", bytes.substr(0, bytes.size() / 2));
  const auto broken = testing::ValidateUsd(dir / "broken.usdz", dir.path());
  ASSERT_TRUE(broken);
  EXPECT_FALSE((*broken)["ok"].get<bool>());
  EXPECT_NE(flat.find("def Scope \"Objects\""), std::string::npos);
  EXPECT_NE(flat.find("def Scope \"People\""), std::string::npos);
}

}  // namespace
}  // namespace semrec::usd
