// GlContext::read_pixels, shared by every backend (reads through the context's own entry points).
#include "render/gl_context.h"

#include <GL/glcorearb.h>

#include <cstring>

#include "engine/core/error.h"

namespace dynscope::render {

Image GlContext::read_pixels() {
  auto bind_framebuffer =
      reinterpret_cast<PFNGLBINDFRAMEBUFFERPROC>(get_proc_address("glBindFramebuffer"));
  auto pixel_store = reinterpret_cast<PFNGLPIXELSTOREIPROC>(get_proc_address("glPixelStorei"));
  auto read = reinterpret_cast<PFNGLREADPIXELSPROC>(get_proc_address("glReadPixels"));
  auto finish = reinterpret_cast<PFNGLFINISHPROC>(get_proc_address("glFinish"));
  if (!bind_framebuffer || !pixel_store || !read || !finish) {
    throw Error(backend() + " context: glReadPixels and friends are not available");
  }
  Image image(width(), height());
  finish();
  bind_framebuffer(GL_READ_FRAMEBUFFER, 0);
  pixel_store(GL_PACK_ALIGNMENT, 1);
  std::vector<uint8_t> bottom_up(image.rgba.size());
  read(0, 0, image.width, image.height, GL_RGBA, GL_UNSIGNED_BYTE, bottom_up.data());
  // GL rows start at the bottom; images start at the top.
  const size_t row = static_cast<size_t>(image.width) * 4;
  for (int y = 0; y < image.height; ++y) {
    std::memcpy(image.rgba.data() + y * row, bottom_up.data() + (image.height - 1 - y) * row, row);
  }
  return image;
}

}  // namespace dynscope::render
