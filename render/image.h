// Image: RGBA8 pixels in memory, with the small operations the renderer's outputs need.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace dynscope::render {

/// Largest image dynscope renders, in pixels (4096 x 4096, e.g. 8192 x 2048): a bigger
/// framebuffer, multisampled, needs gigabytes.
constexpr int64_t kMaxImagePixels = int64_t{4096} * 4096;
/// Longest side of an image (GL's viewport and renderbuffer limit on common drivers).
constexpr int kMaxImageSide = 16384;

/// Throws ValueError(`name`, ...) stating the accepted range unless `width` x `height` is at
/// least 1 x 1, at most kMaxImageSide on a side and kMaxImagePixels pixels. The one size rule of
/// every image and context.
void check_image_size(const std::string& name, int width, int height);

/// 8-bit RGBA image, rows top to bottom, `rgba` holds width*height*4 bytes.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> rgba;

  Image() = default;
  /// A width x height image filled with `fill` (RGBA); throws ValueError if a size is negative.
  Image(int width, int height, std::array<uint8_t, 4> fill = {0, 0, 0, 255});

  bool empty() const { return width == 0 || height == 0; }
  uint8_t* pixel(int x, int y) { return rgba.data() + (static_cast<size_t>(y) * width + x) * 4; }
  const uint8_t* pixel(int x, int y) const {
    return rgba.data() + (static_cast<size_t>(y) * width + x) * 4;
  }
};

/// Box-filtered copy with each side divided by `factor` (>= 1, rounded down, at least 1 pixel).
Image downscale(const Image& image, int factor);
/// Copies `src` into `dst` with its top-left corner at (x, y), clipped to `dst`.
void blit(Image& dst, const Image& src, int x, int y);
/// Fills the rectangle [x, x+w) x [y, y+h) (clipped) with an opaque colour.
void fill_rect(Image& image, int x, int y, int w, int h, std::array<uint8_t, 3> color);
/// Draws `text` with a built-in 5x7 pixel font scaled by `scale` (letters shown upper case;
/// characters without a glyph become blanks). Returns the width drawn in pixels.
int draw_text(Image& image, int x, int y, const std::string& text, std::array<uint8_t, 3> color,
              int scale = 1);
/// Width in pixels that draw_text would use.
int text_width(const std::string& text, int scale = 1);

/// Result of comparing two images of the same size channel by channel.
struct ImageComparison {
  double fraction_within = 0.0;  ///< Pixels whose channels all differ by <= tolerance.
  int max_difference = 0;        ///< Largest channel difference over the image.
  Image diff;  ///< Per pixel: grey copy of `expected`, red where out of tolerance.
};

/// Compares `actual` against `expected`; throws ValueError if their sizes differ.
ImageComparison compare_images(const Image& actual, const Image& expected, int tolerance);

}  // namespace dynscope::render
