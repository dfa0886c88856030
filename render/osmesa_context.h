// OSMesa context: headless GL 4.5 core profile (llvmpipe) rendering into a buffer in memory.
#pragma once

#include <vector>

#include "render/gl_context.h"

struct osmesa_context;

namespace dynscope::render {

/// Off-screen GL core-profile context; works without a display. Include only where a program
/// picks its context (context_factory.cpp).
class OsMesaContext : public GlContext {
 public:
  /// Creates a core-profile context (GL 3.3 or newer) with an RGBA8 + depth24 buffer of the given
  /// size and makes it current. Throws ValueError for sizes < 1, Error if OSMesa refuses.
  OsMesaContext(int width, int height);
  ~OsMesaContext() override;
  OsMesaContext(const OsMesaContext&) = delete;
  OsMesaContext& operator=(const OsMesaContext&) = delete;

  void make_current() override;
  int width() const override { return width_; }
  int height() const override { return height_; }
  void resize(int width, int height) override;
  void swap_buffers() override;
  void* get_proc_address(const char* name) override;
  std::string backend() const override { return "osmesa"; }

 private:
  struct osmesa_context* context_ = nullptr;
  int width_ = 0;
  int height_ = 0;
  std::vector<unsigned char> buffer_;
};

}  // namespace dynscope::render
