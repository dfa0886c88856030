// Tests of the progress reporter's text and bookkeeping.
#include "engine/core/progress.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <thread>
#include <vector>

namespace dynscope {
namespace {

std::string read_all(std::FILE* f) {
  std::rewind(f);
  std::string s;
  char buf[256];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) s.append(buf, n);
  return s;
}

TEST(ProgressTest, FormatsDurations) {
  EXPECT_EQ(Progress::format_duration(5.2), "5s");
  EXPECT_EQ(Progress::format_duration(65), "1m05s");
  EXPECT_EQ(Progress::format_duration(3720), "1h02m");
  EXPECT_EQ(Progress::format_duration(-1), "?");
}

TEST(ProgressTest, LineShowsCountsPercentAndBar) {
  Progress p("train", 10, Progress::Style::kSilent);
  p.advance(4);
  const std::string line = p.render_line(10);
  EXPECT_NE(line.find("train [####......] 40% 4/10"), std::string::npos) << line;
  EXPECT_NE(line.find("/s"), std::string::npos);
  EXPECT_NE(line.find("ETA"), std::string::npos);
  p.set_status("loss 0.5");
  EXPECT_NE(p.render_line(0).find("loss 0.5"), std::string::npos);
}

TEST(ProgressTest, PlainLinesEndWithFinalReport) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    Progress p("generate", 3, Progress::Style::kLines, f);
    for (int i = 0; i < 3; ++i) p.advance();
  }
  const std::string out = read_all(f);
  std::fclose(f);
  EXPECT_NE(out.find("generate 100% 3/3"), std::string::npos) << out;
  EXPECT_EQ(out.find('\r'), std::string::npos) << "plain lines must not use carriage returns";
  EXPECT_EQ(out.back(), '\n');
}

TEST(ProgressTest, FinishDoesNotRepeatAPrintedFinalLine) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    Progress p("eval", 1, Progress::Style::kLines, f);
    p.advance();  // the first advance always prints: "eval 100% 1/1 ..."
  }
  const std::string out = read_all(f);
  std::fclose(f);
  EXPECT_EQ(out.find("100%"), out.rfind("100%")) << out;
}

TEST(ProgressTest, BarStyleRedrawsInPlace) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    Progress p("x", 2, Progress::Style::kBar, f);
    p.advance(2);
  }
  const std::string out = read_all(f);
  std::fclose(f);
  EXPECT_EQ(out.front(), '\r');
  EXPECT_NE(out.find("100% 2/2"), std::string::npos);
}

TEST(ProgressTest, ConcurrentAdvanceCountsEveryUnit) {
  Progress p("threads", 4000, Progress::Style::kSilent);
  std::vector<std::thread> workers;
  for (int t = 0; t < 4; ++t) {
    workers.emplace_back([&] {
      for (int i = 0; i < 1000; ++i) p.advance();
    });
  }
  for (auto& w : workers) w.join();
  EXPECT_EQ(p.done(), 4000);
}

TEST(ProgressTest, UnknownTotalShowsCountOnly) {
  Progress p("scan", 0, Progress::Style::kSilent);
  p.advance(7);
  const std::string line = p.render_line(10);
  EXPECT_NE(line.find("scan 7"), std::string::npos) << line;
  EXPECT_EQ(line.find('%'), std::string::npos);
  EXPECT_LT(p.eta_seconds(), 0);
}

}  // namespace
}  // namespace dynscope
