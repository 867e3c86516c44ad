#include "semrec/core/progress.h"

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "semrec/core/error.h"

namespace semrec {
namespace {

std::string ReadAll(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string out;
  char buf[256];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof(buf), f)) > 0) out.append(buf, n);
  return out;
}

TEST(Progress, LineModePrintsFinalSummary) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressOptions options;
    options.mode = ProgressOptions::Mode::kLines;
    options.line_interval_s = 1e9;  // only the first tick and the final line
    Progress progress("integrate", 4, options, f);
    for (int i = 0; i < 4; ++i) progress.Tick();
  }
  const std::string text = ReadAll(f);
  std::fclose(f);
  EXPECT_NE(text.find("integrate 1/4"), std::string::npos) << text;
  EXPECT_NE(text.find("integrate 4/4 100%"), std::string::npos) << text;
  EXPECT_EQ(text.find('\r'), std::string::npos) << "line mode must not redraw";
  EXPECT_EQ(text.find("4/4"), text.rfind("4/4"))
      << "completion reported twice: " << text;
}

TEST(Progress, LineModeDoesNotRepeatCompletion) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    ProgressOptions options;
    options.mode = ProgressOptions::Mode::kLines;
    options.line_interval_s = 0.0;  // every tick prints
    Progress progress("write", 2, options, f);
    progress.Tick();
    progress.Tick();
  }
  const std::string text = ReadAll(f);
  std::fclose(f);
  EXPECT_EQ(text.find("write 2/2"), text.rfind("write 2/2")) << text;
  EXPECT_NE(text.find("write 1/2"), std::string::npos) << text;
}

TEST(Progress, BarModeRedrawsWithBarAndEta) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  ProgressOptions options;
  options.mode = ProgressOptions::Mode::kBar;
  options.min_interval_s = 0.0;
  options.bar_width = 10;
  Progress progress("fuse", 10, options, f);
  progress.Tick(5);
  EXPECT_NE(progress.Render(true).find("[#####-----] 5/10"), std::string::npos)
      << progress.Render(true);
  EXPECT_NE(progress.Render(true).find("ETA"), std::string::npos);
  progress.Finish();
  const std::string text = ReadAll(f);
  std::fclose(f);
  EXPECT_NE(text.find('\r'), std::string::npos);
  EXPECT_EQ(text.back(), '\n');
}

TEST(Progress, OffPrintsNothingAndOptionsAreChecked) {
  std::FILE* f = std::tmpfile();
  ProgressOptions off;
  off.mode = ProgressOptions::Mode::kOff;
  {
    Progress progress("quiet", 3, off, f);
    progress.Tick(3);
  }
  EXPECT_TRUE(ReadAll(f).empty());
  std::fclose(f);
  ProgressOptions bad;
  bad.bar_width = 0;
  EXPECT_THROW(Progress("x", 1, bad, nullptr), InvalidArgument);
}

TEST(Progress, OnTickSeesEveryTickEvenWhenOff) {
  ProgressOptions off;
  off.mode = ProgressOptions::Mode::kOff;
  std::vector<std::pair<size_t, size_t>> seen;
  off.on_tick = [&](size_t done, size_t total) {
    seen.emplace_back(done, total);
  };
  Progress progress("quiet", 4, off, nullptr);
  progress.Tick();
  progress.Tick(2);
  progress.Finish();
  progress.Tick();  // after Finish: ignored
  const std::vector<std::pair<size_t, size_t>> expected = {{1, 4}, {3, 4}};
  EXPECT_EQ(seen, expected);
}

TEST(FormatDuration, Units) {
  EXPECT_EQ(FormatDuration(12.34), "12.3s");
  EXPECT_EQ(FormatDuration(185), "3m05s");
  EXPECT_EQ(FormatDuration(3725), "1h02m");
}

}  // namespace
}  // namespace semrec
