// Tests of log level parsing and filtering.
#include "engine/core/log.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"

namespace dynscope {
namespace {

TEST(LogTest, ParsesLevelsAndRejectsUnknown) {
  EXPECT_EQ(parse_log_level("debug"), LogLevel::kDebug);
  EXPECT_EQ(parse_log_level("warn"), LogLevel::kWarn);
  EXPECT_EQ(parse_log_level("quiet"), LogLevel::kQuiet);
  try {
    parse_log_level("loud");
    FAIL() << "expected ValueError";
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("loud"), std::string::npos);
  }
}

TEST(LogTest, FiltersBelowLevel) {
  const LogLevel saved = log_level();
  set_log_level(LogLevel::kWarn);
  testing::internal::CaptureStderr();
  log_info("hidden ", 1);
  log_warn("shown ", 2);
  const std::string err = testing::internal::GetCapturedStderr();
  set_log_level(saved);
  EXPECT_EQ(err.find("hidden"), std::string::npos);
  EXPECT_NE(err.find("[warn] shown 2"), std::string::npos) << err;
}

}  // namespace
}  // namespace dynscope
