#include "engine/core/allocator.h"

#include <malloc.h>

#include <atomic>

namespace dynscope {
namespace {

std::atomic<bool> g_configured{false};

}  // namespace

void configure_allocator() {
  if (g_configured.exchange(true)) return;
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 128 << 20);
  mallopt(M_TOP_PAD, 16 << 20);
}

std::string allocator_settings() {
  return g_configured.load()
             ? "dynscope (mmap threshold 32 MiB, trim threshold 128 MiB, top pad 16 MiB)"
             : "glibc defaults";
}

}  // namespace dynscope
