// GlContext: the small interface every GL context offers (OSMesa off-screen, GLFW window, ...).
#pragma once

#include <string>

#include "render/image.h"

namespace dynscope::render {

/// A GL 3.3+ core context with a default framebuffer of width() x height() pixels. The renderer
/// only sees this interface; which concrete context it is, is chosen by the program (see
/// context_factory.h). Entry points are loaded through get_proc_address, never linked.
class GlContext {
 public:
  virtual ~GlContext() = default;

  /// Makes this context current on the calling thread; throws Error if that fails.
  virtual void make_current() = 0;
  /// Framebuffer width in pixels.
  virtual int width() const = 0;
  /// Framebuffer height in pixels.
  virtual int height() const = 0;
  /// Resizes the default framebuffer (window or off-screen buffer); throws ValueError if w or h
  /// < 1.
  virtual void resize(int width, int height) = 0;
  /// Presents the back buffer (a window) or finishes drawing (off-screen).
  virtual void swap_buffers() = 0;
  /// Address of GL entry point `name` ("glClear") for this context, or nullptr if unknown.
  virtual void* get_proc_address(const char* name) = 0;
  /// Short name of the backend ("osmesa", "glfw").
  virtual std::string backend() const = 0;

  /// Reads the default framebuffer as RGBA8, rows top to bottom (the context must be current).
  Image read_pixels();
};

}  // namespace dynscope::render
