#include "engine/core/allocator.h"

#include <malloc.h>

#include <atomic>

namespace dynscope {
namespace {

std::atomic<bool> g_configured{false};
constexpr int kMmapThresholdMiB = 32;   // blocks above this are mapped on their own
constexpr int kTrimThresholdMiB = 128;  // freed memory kept for reuse
constexpr int kTopPadMiB = 16;          // heap growth step

}  // namespace

void configure_allocator() {
  if (g_configured.exchange(true)) return;
  mallopt(M_MMAP_THRESHOLD, kMmapThresholdMiB << 20);
  mallopt(M_TRIM_THRESHOLD, kTrimThresholdMiB << 20);
  mallopt(M_TOP_PAD, kTopPadMiB << 20);
}

std::string allocator_settings() {
  if (!g_configured.load()) return "glibc defaults";
  return "dynscope (mmap threshold " + std::to_string(kMmapThresholdMiB) + " MiB, trim threshold " +
         std::to_string(kTrimThresholdMiB) + " MiB, top pad " + std::to_string(kTopPadMiB) +
         " MiB)";
}

}  // namespace dynscope
