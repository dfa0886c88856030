// Contact sheet composition (CPU only).
#include "render/contact_sheet.h"

#include <algorithm>
#include <cmath>

#include "engine/core/error.h"

namespace dynscope::render {

Image make_contact_sheet(const std::vector<Image>& thumbnails,
                         const std::vector<std::string>& captions, int columns, int padding) {
  if (thumbnails.empty()) throw ValueError("contact sheet", "no thumbnails");
  if (captions.size() != thumbnails.size()) {
    throw ValueError("contact sheet", std::to_string(captions.size()) + " captions for " +
                                          std::to_string(thumbnails.size()) + " thumbnails");
  }
  const int count = static_cast<int>(thumbnails.size());
  if (columns <= 0) columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(count))));
  columns = std::min(columns, count);
  const int rows = (count + columns - 1) / columns;
  int cell_w = 0, cell_h = 0;
  for (const Image& t : thumbnails) {
    cell_w = std::max(cell_w, t.width);
    cell_h = std::max(cell_h, t.height);
  }
  Image sheet(columns * cell_w + (columns + 1) * padding, rows * cell_h + (rows + 1) * padding,
              {255, 255, 255, 255});
  for (int i = 0; i < count; ++i) {
    const int x = padding + (i % columns) * (cell_w + padding);
    const int y = padding + (i / columns) * (cell_h + padding);
    blit(sheet, thumbnails[i], x, y);
    if (!captions[i].empty()) {
      // A white box behind the caption keeps it readable on any image.
      fill_rect(sheet, x, y, text_width(captions[i]) + 4, 11, {255, 255, 255});
      draw_text(sheet, x + 2, y + 2, captions[i], {20, 20, 20});
    }
  }
  return sheet;
}

std::vector<int> contact_sheet_frames(int first, int last, int max_count) {
  std::vector<int> frames;
  if (last < first || max_count < 1) return frames;
  const int total = last - first + 1;
  if (total <= max_count) {
    for (int f = first; f <= last; ++f) frames.push_back(f);
    return frames;
  }
  if (max_count == 1) return {first};
  for (int i = 0; i < max_count; ++i) {
    frames.push_back(first + static_cast<int>(std::lround(static_cast<double>(i) * (total - 1) /
                                                          (max_count - 1))));
  }
  frames.erase(std::unique(frames.begin(), frames.end()), frames.end());
  return frames;
}

}  // namespace dynscope::render
