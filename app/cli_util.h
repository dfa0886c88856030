// Small helpers shared by the subcommands (formatting, file checks).
#pragma once

#include <string>

#include "engine/core/types.h"

namespace dynscope::app {

/// "[x0, y0, z0] .. [x1, y1, z1]" with 3 decimals, or "empty".
std::string format_aabb(const Aabb& box);
/// Throws IoError if `path` does not exist or is not a regular readable file.
void require_readable_file(const std::string& path);

}  // namespace dynscope::app
