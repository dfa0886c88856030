// Levelled logging to stderr, shared by every command.
#pragma once

#include <sstream>
#include <string>

namespace dynscope {

enum class LogLevel { kDebug = 0, kInfo = 1, kWarn = 2, kError = 3, kQuiet = 4 };

/// Sets the minimum level written (default kInfo, or $DYNSCOPE_LOG_LEVEL=debug|info|warn|error).
void set_log_level(LogLevel level);
/// Current minimum level.
LogLevel log_level();
/// Parses "debug", "info", "warn", "error" or "quiet"; throws ValueError otherwise.
LogLevel parse_log_level(const std::string& name);
/// Writes one line "[level] message" to stderr if `level` is enabled (thread-safe).
void log_line(LogLevel level, const std::string& message);

namespace detail {
template <typename... Args>
std::string concat(const Args&... args) {
  std::ostringstream os;
  (os << ... << args);
  return os.str();
}
}  // namespace detail

template <typename... Args>
void log_debug(const Args&... args) {
  if (log_level() <= LogLevel::kDebug) log_line(LogLevel::kDebug, detail::concat(args...));
}
template <typename... Args>
void log_info(const Args&... args) {
  if (log_level() <= LogLevel::kInfo) log_line(LogLevel::kInfo, detail::concat(args...));
}
template <typename... Args>
void log_warn(const Args&... args) {
  if (log_level() <= LogLevel::kWarn) log_line(LogLevel::kWarn, detail::concat(args...));
}
template <typename... Args>
void log_error(const Args&... args) {
  if (log_level() <= LogLevel::kError) log_line(LogLevel::kError, detail::concat(args...));
}

}  // namespace dynscope
