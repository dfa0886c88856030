// Image operations: downscaling, blitting, a tiny bitmap font and image comparison.
#include "render/image.h"

#include <algorithm>
#include <cstdlib>

#include "engine/core/error.h"

namespace dynscope::render {
namespace {

// 5x7 glyphs, one byte per row, bit 4 = leftmost column.
struct Glyph {
  char c;
  uint8_t rows[7];
};

constexpr Glyph kGlyphs[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}},
    {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}},
    {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}},
    {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}},
    {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}},
    {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}},
    {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}},
    {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}},
    {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}},
    {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}},
    {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}},
    {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}},
    {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}},
    {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}},
    {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}},
    {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}},
    {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}},
    {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}},
    {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {'#', {0x0A, 0x0A, 0x1F, 0x0A, 0x1F, 0x0A, 0x0A}},
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}},
    {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},
};

const Glyph* find_glyph(char c) {
  if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  for (const Glyph& g : kGlyphs) {
    if (g.c == c) return &g;
  }
  return nullptr;
}

constexpr int kAdvance = 6;  // 5 columns plus one of spacing

}  // namespace

void check_image_size(const std::string& name, int width, int height) {
  const int64_t pixels = int64_t{width} * height;
  if (width >= 1 && height >= 1 && width <= kMaxImageSide && height <= kMaxImageSide &&
      pixels <= kMaxImagePixels) {
    return;
  }
  throw ValueError(name, "must be at least 1x1, at most " + std::to_string(kMaxImageSide) +
                             " on a side and " + std::to_string(kMaxImagePixels) +
                             " pixels (e.g. 4096x4096), got " + std::to_string(width) + "x" +
                             std::to_string(height));
}

Image::Image(int w, int h, std::array<uint8_t, 4> fill) : width(w), height(h) {
  if (w < 0 || h < 0) {
    throw ValueError("image size", std::to_string(w) + "x" + std::to_string(h));
  }
  rgba.resize(static_cast<size_t>(w) * h * 4);
  for (size_t i = 0; i < rgba.size(); i += 4) std::copy(fill.begin(), fill.end(), &rgba[i]);
}

Image downscale(const Image& image, int factor) {
  if (factor < 1) throw ValueError("downscale factor", std::to_string(factor) + " < 1");
  const int w = std::max(1, image.width / factor);
  const int h = std::max(1, image.height / factor);
  Image out(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      int sum[4] = {0, 0, 0, 0};
      int count = 0;
      for (int dy = 0; dy < factor && y * factor + dy < image.height; ++dy) {
        for (int dx = 0; dx < factor && x * factor + dx < image.width; ++dx) {
          const uint8_t* p = image.pixel(x * factor + dx, y * factor + dy);
          for (int c = 0; c < 4; ++c) sum[c] += p[c];
          ++count;
        }
      }
      uint8_t* q = out.pixel(x, y);
      for (int c = 0; c < 4; ++c) q[c] = static_cast<uint8_t>((sum[c] + count / 2) / count);
    }
  }
  return out;
}

void blit(Image& dst, const Image& src, int x, int y) {
  for (int sy = 0; sy < src.height; ++sy) {
    const int ty = y + sy;
    if (ty < 0 || ty >= dst.height) continue;
    for (int sx = 0; sx < src.width; ++sx) {
      const int tx = x + sx;
      if (tx < 0 || tx >= dst.width) continue;
      std::copy_n(src.pixel(sx, sy), 4, dst.pixel(tx, ty));
    }
  }
}

void fill_rect(Image& image, int x, int y, int w, int h, std::array<uint8_t, 3> color) {
  for (int yy = std::max(0, y); yy < std::min(image.height, y + h); ++yy) {
    for (int xx = std::max(0, x); xx < std::min(image.width, x + w); ++xx) {
      uint8_t* p = image.pixel(xx, yy);
      p[0] = color[0];
      p[1] = color[1];
      p[2] = color[2];
      p[3] = 255;
    }
  }
}

int text_width(const std::string& text, int scale) {
  return text.empty() ? 0 : (static_cast<int>(text.size()) * kAdvance - 1) * scale;
}

int draw_text(Image& image, int x, int y, const std::string& text, std::array<uint8_t, 3> color,
              int scale) {
  int cx = x;
  for (char c : text) {
    if (const Glyph* g = find_glyph(c)) {
      for (int row = 0; row < 7; ++row) {
        for (int col = 0; col < 5; ++col) {
          if (g->rows[row] & (0x10 >> col)) {
            fill_rect(image, cx + col * scale, y + row * scale, scale, scale, color);
          }
        }
      }
    }
    cx += kAdvance * scale;
  }
  return text_width(text, scale);
}

ImageComparison compare_images(const Image& actual, const Image& expected, int tolerance) {
  if (actual.width != expected.width || actual.height != expected.height) {
    throw ValueError("image size", "actual " + std::to_string(actual.width) + "x" +
                                       std::to_string(actual.height) + " vs expected " +
                                       std::to_string(expected.width) + "x" +
                                       std::to_string(expected.height));
  }
  ImageComparison result;
  result.diff = Image(expected.width, expected.height);
  size_t within = 0;
  for (int y = 0; y < expected.height; ++y) {
    for (int x = 0; x < expected.width; ++x) {
      const uint8_t* a = actual.pixel(x, y);
      const uint8_t* e = expected.pixel(x, y);
      int worst = 0;
      for (int c = 0; c < 4; ++c) worst = std::max(worst, std::abs(int(a[c]) - int(e[c])));
      result.max_difference = std::max(result.max_difference, worst);
      uint8_t* d = result.diff.pixel(x, y);
      if (worst <= tolerance) {
        ++within;
        const uint8_t grey = static_cast<uint8_t>((e[0] + e[1] + e[2]) / 6 + 128);
        d[0] = d[1] = d[2] = grey;
      } else {
        d[0] = 255;
        d[1] = d[2] = 0;
      }
    }
  }
  const size_t total = static_cast<size_t>(expected.width) * expected.height;
  result.fraction_within = total ? static_cast<double>(within) / total : 1.0;
  return result;
}

}  // namespace dynscope::render
