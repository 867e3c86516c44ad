#include "semrec/core/label_map.h"

#include <set>

#include <gtest/gtest.h>

namespace semrec {
namespace {

TEST(LabelSet, AddFindAndReject) {
  LabelSet voc("voc");
  voc.Add({0, "background", {0, 0, 0}});
  voc.Add({15, "person", {192, 128, 128}});
  EXPECT_EQ(voc.size(), 2u);
  EXPECT_EQ(voc.Get(15).name, "person");
  EXPECT_EQ(voc.FindByName("person"), 15);
  EXPECT_FALSE(voc.FindByName("cat").has_value());
  EXPECT_THROW(voc.Add({15, "other", {}}), InvalidArgument);
  EXPECT_THROW(voc.Add({16, "person", {}}), InvalidArgument);
  EXPECT_THROW(voc.Add({17, "", {}}), InvalidArgument);
  EXPECT_THROW(voc.Get(3), InvalidArgument);
  EXPECT_EQ(voc.Classes().back().id, 15);
}

TEST(LabelMap, Histogram) {
  LabelMap map(3, 2);
  map.values() = {0, 5, 5, 7, 5, 0};
  const auto h = LabelHistogram(map);
  ASSERT_EQ(h.size(), 3u);
  EXPECT_EQ(h.at(0), 2u);
  EXPECT_EQ(h.at(5), 3u);
  EXPECT_EQ(h.at(7), 1u);
}

TEST(LabelColor, DistinctForFirstIds) {
  std::set<std::array<uint8_t, 3>> colors;
  for (uint32_t id = 1; id <= 64; ++id) colors.insert(LabelColor(id));
  EXPECT_EQ(colors.size(), 64u);
  EXPECT_EQ(LabelColor(0), (std::array<uint8_t, 3>{0, 0, 0}));
}

}  // namespace
}  // namespace semrec
