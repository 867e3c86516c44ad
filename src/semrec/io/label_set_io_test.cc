#include "semrec/io/label_set_io.h"

#include <sstream>

#include <gtest/gtest.h>

#include "semrec/core/file_util.h"

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace semrec::io {
namespace {

TEST(LabelSets, ShippedSetsHaveTheDocumentedClasses) {
  const LabelSet voc = LoadLabelSet("voc");
  ASSERT_EQ(voc.size(), 21u);
  EXPECT_EQ(voc.Get(0).name, "background");
  EXPECT_EQ(voc.Get(15).name, "person");
  // The PASCAL VOC palette: person is (192, 128, 128).
  EXPECT_EQ(voc.Get(15).color, (std::array<uint8_t, 3>{192, 128, 128}));
  const LabelSet ade = LoadLabelSet("ade20k");
  ASSERT_EQ(ade.size(), 150u);
  EXPECT_EQ(ade.Get(1).name, "wall");
  EXPECT_EQ(ade.Get(13).name, "person");
  EXPECT_FALSE(ade.Contains(0));  // 0 = unlabelled in ADE20K annotations
  const LabelSet coco = LoadLabelSet("coco80");
  ASSERT_EQ(coco.size(), 80u);
  EXPECT_EQ(coco.Get(1).name, "person");
  EXPECT_EQ(coco.Get(80).name, "toothbrush");
  const LabelSet cs = LoadLabelSet("cityscapes");
  ASSERT_EQ(cs.size(), 19u);
  EXPECT_EQ(cs.Get(1).name, "road");
  EXPECT_EQ(cs.Get(19).name, "bicycle");
}

TEST(LabelSets, ShippedSetsSayWhereStructureLiesAndHowLargeFurnitureIs) {
  // Fusion's structure gate and its fit rule read these (LabelClass); the
  // same class under another set's name carries the same data.
  const auto get = [](const LabelSet& set, const std::string& name) {
    const auto id = set.FindByName(name);
    EXPECT_TRUE(id.has_value()) << set.name() << ": " << name;
    return id ? set.Get(*id) : LabelClass{};
  };
  for (const char* name : {"ade20k-top31", "ade20k", "nyu40"}) {
    SCOPED_TRACE(name);
    const LabelSet set = LoadLabelSet(name);
    EXPECT_EQ(get(set, "wall").geometry, StructureGeometry::kVertical);
    EXPECT_EQ(get(set, "floor").geometry, StructureGeometry::kFloor);
    EXPECT_EQ(get(set, "ceiling").geometry, StructureGeometry::kCeiling);
    EXPECT_EQ(get(set, "chair").max_length_m, 0.75);
    EXPECT_EQ(get(set, "sofa").max_length_m, 3.0);
    EXPECT_EQ(get(set, "sofa").max_width_m, 1.2);
    EXPECT_EQ(get(set, "table").max_width_m, 1.3);
    EXPECT_EQ(get(set, "cabinet").max_length_m, 0.0);  // sizes vary
    EXPECT_TRUE(get(set, "cabinet").furniture_front);
    EXPECT_FALSE(get(set, "chair").furniture_front);
  }
  EXPECT_TRUE(get(LoadLabelSet("nyu40"), "dresser").furniture_front);
  EXPECT_EQ(get(LoadLabelSet("ade20k"), "sky").geometry,
            StructureGeometry::kNone);
  EXPECT_EQ(get(LoadLabelSet("ade20k"), "rug").geometry,
            StructureGeometry::kFloor);
  // Other names for the same furniture.
  EXPECT_EQ(get(LoadLabelSet("coco80"), "couch").max_length_m, 3.0);
  EXPECT_EQ(get(LoadLabelSet("coco80"), "dining table").max_width_m, 1.3);
  EXPECT_EQ(get(LoadLabelSet("voc21"), "diningtable").max_width_m, 1.3);
  EXPECT_EQ(get(LoadLabelSet("ade20k"), "coffee").max_length_m, 1.5);
}

TEST(LabelSets, StructurePlanesAndFootprintsSurviveWritingAndReading) {
  LabelSet set("mine");
  LabelClass wall{1, "wall", {200, 200, 200}, ClassKind::kStuff};
  wall.geometry = StructureGeometry::kVertical;
  LabelClass bench{2, "bench", {10, 20, 30}, ClassKind::kThing};
  bench.max_length_m = 2.2;
  bench.max_width_m = 0.8;
  bench.furniture_front = true;
  set.Add(wall);
  set.Add(bench);
  set.Add({3, "box", {1, 2, 3}, ClassKind::kThing});
  semrec::testing::TempDir dir;
  WriteLabelSetJson(dir.path() / "classes.json", set);
  const LabelSet back = ReadLabelSetJson(dir.path() / "classes.json");
  EXPECT_EQ(back.Get(1).geometry, StructureGeometry::kVertical);
  EXPECT_EQ(back.Get(2).max_length_m, 2.2);
  EXPECT_EQ(back.Get(2).max_width_m, 0.8);
  EXPECT_TRUE(back.Get(2).furniture_front);
  EXPECT_FALSE(back.Get(3).furniture_front);
  EXPECT_EQ(back.Get(3).max_length_m, 0.0);
  EXPECT_EQ(back.Get(3).geometry, StructureGeometry::kNone);
  // A list that says nothing of either (older outputs, hand-written) takes
  // them from the shipped sets by name; one that says anything is taken as is.
  semrec::testing::WriteText(
      dir.path() / "old.json",
      "[{\"id\": 1, \"name\": \"wall\", \"kind\": \"stuff\"}, "
      "{\"id\": 2, \"name\": \"chair\", \"kind\": \"thing\"}, "
      "{\"id\": 3, \"name\": \"counter\", \"kind\": \"thing\"}]");
  const LabelSet old = ReadLabelSetJson(dir.path() / "old.json");
  EXPECT_EQ(old.Get(1).geometry, StructureGeometry::kVertical);
  EXPECT_EQ(old.Get(2).max_length_m, 0.75);
  EXPECT_TRUE(old.Get(3).furniture_front);
  semrec::testing::WriteText(
      dir.path() / "said.json",
      "[{\"id\": 1, \"name\": \"wall\", \"kind\": \"stuff\", "
      "\"structure\": \"none\"}, "
      "{\"id\": 2, \"name\": \"chair\", \"kind\": \"thing\"}]");
  const LabelSet said = ReadLabelSetJson(dir.path() / "said.json");
  EXPECT_EQ(said.Get(1).geometry, StructureGeometry::kNone);
  EXPECT_EQ(said.Get(2).max_length_m, 0.0);
  // Data that cannot be meant is refused with the file and the class named.
  for (const auto& [text, message] :
       {std::pair{"[{\"id\": 1, \"name\": \"wall\", \"kind\": "
                  "\"stuff\", \"structure\": \"slanted\"}]",
                  "structure 'slanted' is not"},
        std::pair{"[{\"id\": 1, \"name\": \"chair\", \"kind\": "
                  "\"thing\", \"structure\": \"floor\"}]",
                  "'chair' has a structure plane"},
        std::pair{"[{\"id\": 1, \"name\": \"sofa\", \"kind\": "
                  "\"thing\", \"footprint_m\": [1.2, 3.0]}]",
                  "length >= width > 0"},
        std::pair{"[{\"id\": 1, \"name\": \"floor\", \"kind\": "
                  "\"stuff\", \"footprint_m\": [3.0, 1.2]}]",
                  "a footprint needs a thing"},
        std::pair{"[{\"id\": 1, \"name\": \"wall\", \"kind\": "
                  "\"stuff\", \"front\": true}]",
                  "furniture front but not a thing"},
        std::pair{"[{\"id\": 1, \"name\": \"sofa\", \"kind\": "
                  "\"thing\", \"footprint_m\": [3.0]}]",
                  "class 0"}}) {
    semrec::testing::WriteText(dir.path() / "bad.json", text);
    try {
      ReadLabelSetJson(dir.path() / "bad.json");
      ADD_FAILURE() << text << " accepted";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.json"), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos)
          << e.what();
    }
  }
}

TEST(LabelSets, AdeNamesMatchTheDatasetsObjectInfo) {
  SEMREC_REQUIRE_SAMPLE_DATA(ade_dir, "ade20k_val_3");
  const std::string csv = ReadTextFile(ade_dir / "objectInfo150.csv");
  const LabelSet ade = LoadLabelSet("ade20k150");
  // Each row "Idx,...,Name" of the dataset's table names our class Idx (first
  // synonym; three ambiguous "screen" rows are spelled out in our file).
  std::istringstream lines(csv);
  std::string line;
  std::getline(lines, line);  // header
  int rows = 0;
  while (std::getline(lines, line)) {
    if (line.empty()) continue;
    const int id = std::stoi(line.substr(0, line.find(',')));
    const std::string names = line.substr(line.rfind(',') + 1);
    const std::string name = ade.Get(static_cast<uint16_t>(id)).name;
    const std::string first = names.substr(0, names.find(';'));
    if (id == 59 || id == 131 || id == 142) {
      EXPECT_NE(name.find("screen"), std::string::npos) << id;
    } else {
      EXPECT_EQ(name, first) << "class " << id;
    }
    ++rows;
  }
  EXPECT_EQ(rows, 150);
}

TEST(LabelSets, UnknownNamesAndFilesAreRejectedClearly) {
  try {
    LoadLabelSet("voc-2012");
    FAIL() << "expected an error";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("voc-2012"), std::string::npos);
  }
  semrec::testing::TempDir dir;
  semrec::testing::WriteText(dir.path() / "bad.json", "[{\"id\": 1}]");
  EXPECT_THROW(LoadLabelSet((dir.path() / "bad.json").string()), FormatError);
  semrec::testing::WriteText(
      dir.path() / "mine.json",
      "[{\"id\": 3, \"name\": \"mug\", \"kind\": \"thing\"}, "
      "{\"id\": 4, \"name\": \"wall\", \"kind\": \"stuff\"}]");
  const LabelSet mine = LoadLabelSet((dir.path() / "mine.json").string());
  EXPECT_EQ(mine.Get(3).name, "mug");
  EXPECT_EQ(mine.Get(3).kind, ClassKind::kThing);
  EXPECT_EQ(mine.Get(4).kind, ClassKind::kStuff);
  // Every class must say whether it is structure or an object.
  semrec::testing::WriteText(dir.path() / "unmarked.json",
                             "[{\"id\": 3, \"name\": \"mug\"}]");
  semrec::testing::WriteText(
      dir.path() / "badkind.json",
      "[{\"id\": 3, \"name\": \"mug\", \"kind\": \"object\"}]");
  for (const auto& [file, message] :
       {std::pair{"unmarked.json", "class 3 ('mug') has no \"kind\""},
        std::pair{"badkind.json", "kind 'object' is not thing, stuff"}}) {
    try {
      LoadLabelSet((dir.path() / file).string());
      ADD_FAILURE() << file << " accepted";
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(file), std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace semrec::io
