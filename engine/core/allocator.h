// The heap settings of every dynscope process that runs the model or builds neighbour lists.
#pragma once

#include <string>

namespace dynscope {

/// Sets glibc's malloc so that memory a step frees is reused by the next instead of returned to
/// the kernel and faulted in again, zeroed: up to 128 MiB of freed memory kept, the heap grown
/// 16 MiB at a time, only blocks above 32 MiB mapped on their own (so huge buffers still return
/// to the system). Idempotent. LibTorch's runtime calls it when it loads; torch-free programs
/// that measure the same code (geometry_bench) call it at start.
void configure_allocator();

/// The settings in force: "dynscope (...)" after configure_allocator(), else "glibc defaults".
std::string allocator_settings();

}  // namespace dynscope
