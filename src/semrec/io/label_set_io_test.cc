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
