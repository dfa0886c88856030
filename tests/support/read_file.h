// Reads a whole file in a test (binary-safe); an unreadable file reads as "".
#pragma once

#include <fstream>
#include <sstream>
#include <string>

namespace dynscope::test {

inline std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace dynscope::test
