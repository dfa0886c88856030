// Tests of images, PNG files, comparison and the contact sheet.
#include "render/image.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "engine/core/error.h"
#include "render/contact_sheet.h"
#include "render/png_io.h"

namespace dynscope::render {
namespace {

namespace fs = std::filesystem;

fs::path temp_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("dynscope_render_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

Image gradient(int w, int h) {
  Image image(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      uint8_t* p = image.pixel(x, y);
      p[0] = static_cast<uint8_t>(x * 7);
      p[1] = static_cast<uint8_t>(y * 5);
      p[2] = static_cast<uint8_t>(x ^ y);
      p[3] = 255;
    }
  }
  return image;
}

TEST(PngIo, RoundTripIsExact) {
  const fs::path dir = temp_dir("png");
  const Image image = gradient(37, 21);
  write_png((dir / "a.png").string(), image);
  const Image back = read_png((dir / "a.png").string());
  EXPECT_EQ(back.width, 37);
  EXPECT_EQ(back.height, 21);
  EXPECT_EQ(back.rgba, image.rgba);
  // No temporary file is left behind.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);
}

TEST(PngIo, BadFilesGiveIoErrorsNamingThePath) {
  const fs::path dir = temp_dir("png_bad");
  const std::string text = (dir / "not.png").string();
  std::ofstream(text) << "hello";
  try {
    read_png(text);
    FAIL();
  } catch (const IoError& e) {
    EXPECT_EQ(e.path(), text);
  }
  EXPECT_THROW(read_png((dir / "missing.png").string()), IoError);
  EXPECT_THROW(write_png((dir / "no_such_dir" / "x.png").string(), gradient(2, 2)), IoError);
  EXPECT_THROW(write_png((dir / "empty.png").string(), Image()), ValueError);
}

TEST(Image, CompareCountsPixelsOutsideTolerance) {
  const Image a = gradient(10, 10);
  Image b = a;
  b.pixel(3, 4)[0] = static_cast<uint8_t>(b.pixel(3, 4)[0] + 20);
  b.pixel(5, 5)[1] = static_cast<uint8_t>(b.pixel(5, 5)[1] + 5);
  const ImageComparison c = compare_images(b, a, 8);
  EXPECT_DOUBLE_EQ(c.fraction_within, 0.99);
  EXPECT_EQ(c.max_difference, 20);
  EXPECT_EQ(c.diff.pixel(3, 4)[0], 255);
  EXPECT_EQ(c.diff.pixel(3, 4)[1], 0);
  EXPECT_THROW(compare_images(gradient(3, 3), a, 8), ValueError);
}

TEST(Image, DownscaleAveragesBlocks) {
  Image image(4, 2, {0, 0, 0, 255});
  image.pixel(0, 0)[0] = 200;
  image.pixel(1, 1)[0] = 100;
  const Image half = downscale(image, 2);
  ASSERT_EQ(half.width, 2);
  ASSERT_EQ(half.height, 1);
  EXPECT_EQ(half.pixel(0, 0)[0], 75);
  EXPECT_EQ(half.pixel(1, 0)[0], 0);
  EXPECT_THROW(downscale(image, 0), ValueError);
}

TEST(Image, TextDrawsGlyphPixelsOnly) {
  Image image(40, 10, {255, 255, 255, 255});
  const int w = draw_text(image, 1, 1, "12", {0, 0, 0});
  EXPECT_EQ(w, text_width("12"));
  EXPECT_EQ(w, 11);
  int dark = 0;
  for (int y = 0; y < 10; ++y) {
    for (int x = 0; x < 40; ++x) dark += image.pixel(x, y)[0] == 0;
  }
  // "1" has 10 lit cells and "2" has 14 in the 5x7 font.
  EXPECT_EQ(dark, 10 + 14);
  EXPECT_EQ(image.pixel(39, 9)[0], 255);
}

TEST(ContactSheet, LaysOutCellsAndCaptions) {
  std::vector<Image> thumbs(5, Image(30, 20, {0, 0, 255, 255}));
  const Image sheet = make_contact_sheet(thumbs, {"0", "1", "2", "3", "4"}, 3, 4);
  EXPECT_EQ(sheet.width, 3 * 30 + 4 * 4);
  EXPECT_EQ(sheet.height, 2 * 20 + 3 * 4);
  EXPECT_EQ(sheet.pixel(4 + 29, 4 + 19)[2], 255);  // inside cell 0
  EXPECT_EQ(sheet.pixel(0, 0)[2], 255);            // white padding
  EXPECT_EQ(sheet.pixel(0, 0)[0], 255);
  EXPECT_THROW(make_contact_sheet({}, {}), ValueError);
  EXPECT_THROW(make_contact_sheet(thumbs, {"a"}), ValueError);
}

TEST(ContactSheet, FrameSelectionKeepsEndsAndLimit) {
  EXPECT_EQ(contact_sheet_frames(2, 5, 10), (std::vector<int>{2, 3, 4, 5}));
  const std::vector<int> f = contact_sheet_frames(0, 99, 5);
  EXPECT_EQ(f, (std::vector<int>{0, 25, 50, 74, 99}));
  EXPECT_TRUE(contact_sheet_frames(3, 2, 5).empty());
}

}  // namespace
}  // namespace dynscope::render
