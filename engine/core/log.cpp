// Levelled logging to stderr.
#include "engine/core/log.h"

#include <atomic>
#include <cstdlib>
#include <iostream>
#include <mutex>

#include "engine/core/error.h"

namespace dynscope {
namespace {

LogLevel initial_level() {
  const char* env = std::getenv("DYNSCOPE_LOG_LEVEL");
  if (env == nullptr) return LogLevel::kInfo;
  try {
    return parse_log_level(env);
  } catch (const Error&) {
    return LogLevel::kInfo;
  }
}

std::atomic<LogLevel>& level_ref() {
  static std::atomic<LogLevel> level{initial_level()};
  return level;
}

std::mutex& log_mutex() {
  static std::mutex m;
  return m;
}

}  // namespace

void set_log_level(LogLevel level) { level_ref() = level; }
LogLevel log_level() { return level_ref(); }

LogLevel parse_log_level(const std::string& name) {
  if (name == "debug") return LogLevel::kDebug;
  if (name == "info") return LogLevel::kInfo;
  if (name == "warn") return LogLevel::kWarn;
  if (name == "error") return LogLevel::kError;
  if (name == "quiet") return LogLevel::kQuiet;
  throw ValueError("log level", "unknown level '" + name + "' (debug, info, warn, error, quiet)");
}

void log_line(LogLevel level, const std::string& message) {
  static const char* kNames[] = {"debug", "info", "warn", "error", "quiet"};
  std::lock_guard<std::mutex> lock(log_mutex());
  std::cerr << "[" << kNames[static_cast<int>(level)] << "] " << message << "\n";
}

}  // namespace dynscope
