// OSMesa context: headless core-profile GL into a memory buffer (llvmpipe), no display needed.
#include "render/osmesa_context.h"

#include <GL/osmesa.h>

#include "engine/core/error.h"
#include "render/image.h"

namespace dynscope::render {
namespace {

void check_size(int width, int height) { check_image_size("image size", width, height); }

}  // namespace

OsMesaContext::OsMesaContext(int width, int height) {
  check_size(width, height);
  // Ask for the newest core profile first; llvmpipe gives 4.5, older Mesa at least 3.3.
  for (const int minor_major : {45, 33}) {
    const int attribs[] = {OSMESA_FORMAT,
                           OSMESA_RGBA,
                           OSMESA_DEPTH_BITS,
                           24,
                           OSMESA_STENCIL_BITS,
                           0,
                           OSMESA_ACCUM_BITS,
                           0,
                           OSMESA_PROFILE,
                           OSMESA_CORE_PROFILE,
                           OSMESA_CONTEXT_MAJOR_VERSION,
                           minor_major / 10,
                           OSMESA_CONTEXT_MINOR_VERSION,
                           minor_major % 10,
                           0};
    context_ = OSMesaCreateContextAttribs(attribs, nullptr);
    if (context_) break;
  }
  if (!context_) {
    throw Error(
        "osmesa: cannot create a GL 3.3+ core-profile context (is libOSMesa built with "
        "llvmpipe/softpipe?)");
  }
  width_ = width;
  height_ = height;
  buffer_.assign(static_cast<size_t>(width) * height * 4, 0);
  make_current();
}

OsMesaContext::~OsMesaContext() {
  if (context_) OSMesaDestroyContext(context_);
}

void OsMesaContext::make_current() {
  if (!OSMesaMakeCurrent(context_, buffer_.data(), GL_UNSIGNED_BYTE, width_, height_)) {
    throw Error("osmesa: OSMesaMakeCurrent failed for a " + std::to_string(width_) + "x" +
                std::to_string(height_) + " buffer");
  }
}

void OsMesaContext::resize(int width, int height) {
  check_size(width, height);
  if (width == width_ && height == height_) return;
  width_ = width;
  height_ = height;
  buffer_.assign(static_cast<size_t>(width) * height * 4, 0);
  make_current();
}

void OsMesaContext::swap_buffers() {
  auto finish = reinterpret_cast<void (*)()>(OSMesaGetProcAddress("glFinish"));
  if (finish) finish();
}

void* OsMesaContext::get_proc_address(const char* name) {
  return reinterpret_cast<void*>(OSMesaGetProcAddress(name));
}

}  // namespace dynscope::render
