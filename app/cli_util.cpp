// Helpers shared by the subcommands.
#include "app/cli_util.h"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "engine/core/error.h"

namespace dynscope::app {

std::string format_aabb(const Aabb& box) {
  if (box.empty()) return "empty";
  char buf[160];
  std::snprintf(buf, sizeof buf, "[%.3f, %.3f, %.3f] .. [%.3f, %.3f, %.3f]", box.min.x(),
                box.min.y(), box.min.z(), box.max.x(), box.max.y(), box.max.z());
  return buf;
}

void require_readable_file(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path, "no such file");
  if (!fs::is_regular_file(path, ec)) throw IoError(path, "not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot be opened for reading");
}

}  // namespace dynscope::app
