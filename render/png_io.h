// PNG files for rendered images (libpng), written atomically.
#pragma once

#include <string>

#include "render/image.h"

namespace dynscope::render {

/// Writes `image` as an 8-bit RGBA PNG through a temporary file renamed onto `path`, so a failed
/// write never leaves a partial file. Throws IoError naming `path`, ValueError for an empty image.
void write_png(const std::string& path, const Image& image);

/// Reads a PNG (any bit depth / colour type) as RGBA8. Throws IoError naming `path` if the file is
/// missing or not a valid PNG.
Image read_png(const std::string& path);

}  // namespace dynscope::render
