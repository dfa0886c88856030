// Contact sheet: a grid of captioned thumbnails of rendered frames in one image.
#pragma once

#include <string>
#include <vector>

#include "render/image.h"

namespace dynscope::render {

/// Lays `thumbnails` out row by row in `columns` columns (0: about square), each with its
/// caption drawn in its top-left corner, on a white sheet with `padding` pixels between cells.
/// Thumbnails may differ in size (cells take the largest). Throws ValueError if there are no
/// thumbnails or the caption count differs.
Image make_contact_sheet(const std::vector<Image>& thumbnails,
                         const std::vector<std::string>& captions, int columns = 0,
                         int padding = 4);

/// At most `max_count` frame indices spread evenly over [first, last] (inclusive), both ends kept.
std::vector<int> contact_sheet_frames(int first, int last, int max_count);

}  // namespace dynscope::render
