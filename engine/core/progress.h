// Progress reporting for long work: a bar with rate and ETA on a terminal, periodic lines otherwise.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>

namespace dynscope {

/// Reports progress of `total` units of work to a stream (stderr by default).
/// Thread-safe: several workers may call advance() concurrently.
class Progress {
 public:
  enum class Style { kAuto, kBar, kLines, kSilent };

  /// `label` prefixes every report; `total` is the number of units (0 = unknown).
  Progress(std::string label, int64_t total, Style style = Style::kAuto, std::FILE* out = stderr);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Marks `n` more units done and redraws if due.
  void advance(int64_t n = 1);
  /// Sets a short status text shown after the counters (e.g. "loss 0.012").
  void set_status(const std::string& status);
  /// Draws the final state once and ends the line; called by the destructor if not before.
  void finish();

  int64_t done() const { return done_; }
  int64_t total() const { return total_; }
  /// Units per second since construction.
  double rate() const;
  /// Estimated seconds left (negative when unknown).
  double eta_seconds() const;

  /// Formats seconds as "1h02m", "3m05s" or "12s".
  static std::string format_duration(double seconds);
  /// The text of one report (without carriage return or newline); exposed for tests.
  std::string render_line(int bar_width) const;

 private:
  void draw(bool final_draw);

  std::string label_;
  int64_t total_;
  Style style_;
  std::FILE* out_;
  std::atomic<int64_t> done_{0};
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
  std::mutex mutex_;
  std::string status_;
  bool finished_ = false;
  int64_t last_drawn_done_ = -1;
};

}  // namespace dynscope
