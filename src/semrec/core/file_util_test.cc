#include "semrec/core/file_util.h"

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace fs = std::filesystem;

namespace semrec {
namespace {

TEST(WriteFileAtomic, ReplacesOnlyOnSuccess) {
  testing::TempDir dir;
  const fs::path target = dir / "sub/out.txt";
  WriteTextFileAtomic(target, "first");
  EXPECT_EQ(ReadTextFile(target), "first");
  // A failing writer leaves the previous content and no temporary file behind.
  EXPECT_THROW(WriteFileAtomic(target,
                               [](const fs::path& tmp) {
                                 testing::WriteText(tmp, "partial");
                                 throw IoError(tmp, "simulated failure");
                               }),
               IoError);
  EXPECT_EQ(ReadTextFile(target), "first");
  size_t files = 0;
  for ([[maybe_unused]] const auto& e :
       fs::directory_iterator(target.parent_path())) {
    ++files;
  }
  EXPECT_EQ(files, 1u);
}

TEST(WriteFileAtomic, TemporaryKeepsExtension) {
  testing::TempDir dir;
  fs::path seen;
  WriteFileAtomic(dir / "mesh.ply", [&](const fs::path& tmp) {
    seen = tmp;
    testing::WriteText(tmp, "x");
  });
  EXPECT_EQ(seen.extension(), ".ply");
}

TEST(RequireFile, NamesTheFile) {
  try {
    RequireFile("/nonexistent/depth.png", "depth image");
    FAIL();
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()),
              "/nonexistent/depth.png: depth image does not exist");
  }
}

TEST(LowerExtension, LowerCasesOnlyTheLastExtension) {
  EXPECT_EQ(LowerExtension("a/B.PNG"), ".png");
  EXPECT_EQ(LowerExtension("frame.Color.JPG"), ".jpg");
  EXPECT_EQ(LowerExtension("run.Mcap"), ".mcap");
  EXPECT_EQ(LowerExtension("README"), "");
}

}  // namespace
}  // namespace semrec
