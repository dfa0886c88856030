// Progress bar / periodic progress lines.
#include "engine/core/progress.h"

#include <unistd.h>

#include <cmath>
#include <sstream>

namespace dynscope {
namespace {
using Clock = std::chrono::steady_clock;
}

Progress::Progress(std::string label, int64_t total, Style style, std::FILE* out)
    : label_(std::move(label)), total_(total), style_(style), out_(out) {
  if (style_ == Style::kAuto) {
    style_ = (out_ != nullptr && isatty(fileno(out_))) ? Style::kBar : Style::kLines;
  }
  if (out_ == nullptr) style_ = Style::kSilent;
  start_ = Clock::now();
  last_draw_ = start_ - std::chrono::hours(1);
}

Progress::~Progress() { finish(); }

double Progress::rate() const {
  const double s = std::chrono::duration<double>(Clock::now() - start_).count();
  return s > 0 ? static_cast<double>(done_) / s : 0.0;
}

double Progress::eta_seconds() const {
  const double r = rate();
  if (total_ <= 0 || r <= 0) return -1.0;
  return static_cast<double>(total_ - done_) / r;
}

std::string Progress::format_duration(double seconds) {
  if (!(seconds >= 0) || !std::isfinite(seconds)) return "?";
  const auto s = static_cast<int64_t>(std::llround(seconds));
  char buf[32];
  if (s >= 3600) {
    std::snprintf(buf, sizeof buf, "%lldh%02lldm", static_cast<long long>(s / 3600),
                  static_cast<long long>((s % 3600) / 60));
  } else if (s >= 60) {
    std::snprintf(buf, sizeof buf, "%lldm%02llds", static_cast<long long>(s / 60),
                  static_cast<long long>(s % 60));
  } else {
    std::snprintf(buf, sizeof buf, "%llds", static_cast<long long>(s));
  }
  return buf;
}

std::string Progress::render_line(int bar_width) const {
  std::ostringstream os;
  const int64_t done = done_;
  os << label_ << " ";
  if (total_ > 0) {
    const double frac = std::min(1.0, static_cast<double>(done) / static_cast<double>(total_));
    if (bar_width > 0) {
      const int filled = static_cast<int>(frac * bar_width);
      os << "[" << std::string(filled, '#') << std::string(bar_width - filled, '.') << "] ";
    }
    os << static_cast<int>(frac * 100.0) << "% " << done << "/" << total_;
  } else {
    os << done;
  }
  char rate_buf[32];
  std::snprintf(rate_buf, sizeof rate_buf, "%.3g", rate());
  os << " " << rate_buf << "/s";
  if (total_ > 0) {
    os << (done >= total_ ? " elapsed " : " ETA ");
    os << format_duration(done >= total_
                              ? std::chrono::duration<double>(Clock::now() - start_).count()
                              : eta_seconds());
  }
  if (!status_.empty()) os << " " << status_;
  return os.str();
}

void Progress::advance(int64_t n) {
  done_ += n;
  draw(false);
}

void Progress::set_status(const std::string& status) {
  std::lock_guard<std::mutex> lock(mutex_);
  status_ = status;
}

void Progress::draw(bool final_draw) {
  if (style_ == Style::kSilent) return;
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  const auto now = Clock::now();
  // Bars redraw a few times a second; plain lines (logs, CI) every few seconds.
  const auto period =
      style_ == Style::kBar ? std::chrono::milliseconds(100) : std::chrono::milliseconds(5000);
  if (!final_draw && now - last_draw_ < period) return;
  // A plain line already showing the final count is not repeated by finish().
  if (final_draw && style_ == Style::kLines && done_ == last_drawn_done_) return;
  last_draw_ = now;
  last_drawn_done_ = done_;
  if (style_ == Style::kBar) {
    std::fprintf(out_, "\r%s\033[K", render_line(30).c_str());
    if (final_draw) std::fputc('\n', out_);
  } else {
    std::fprintf(out_, "%s\n", render_line(0).c_str());
  }
  std::fflush(out_);
}

void Progress::finish() {
  draw(true);
  std::lock_guard<std::mutex> lock(mutex_);
  finished_ = true;
}

}  // namespace dynscope
