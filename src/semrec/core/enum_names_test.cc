#include "semrec/core/enum_names.h"

#include <gtest/gtest.h>

#include "semrec/core/label_map.h"

namespace semrec {
namespace {

enum class Shade { kLight, kDark };

const char* ShadeName(Shade shade) {
  return shade == Shade::kLight ? "light" : "dark";
}

TEST(ParseEnumName, FindsTheValueAndListsTheNamesWhenNoneFits) {
  EXPECT_EQ(ParseEnumName("dark", {Shade::kLight, Shade::kDark}, ShadeName,
                          "shade"),
            Shade::kDark);
  try {
    ParseEnumName("grey", {Shade::kLight, Shade::kDark}, ShadeName, "shade");
    FAIL() << "no error for an unknown name";
  } catch (const InvalidArgument& e) {
    EXPECT_STREQ(e.what(), "shade must be one of light, dark, not 'grey'");
  }
  // Names are compared exactly: no case folding, no prefixes.
  EXPECT_THROW(
      ParseEnumName("Dark", {Shade::kLight, Shade::kDark}, ShadeName, "shade"),
      InvalidArgument);
}

TEST(ParseEnumName, ClassKindsRoundTrip) {
  for (const ClassKind kind :
       {ClassKind::kThing, ClassKind::kStuff, ClassKind::kOther}) {
    EXPECT_EQ(ParseClassKind(ClassKindName(kind)), kind);
  }
  EXPECT_FALSE(ParseClassKind("things").has_value());
}

}  // namespace
}  // namespace semrec
