// Temporary file + rename, so that writers never leave partial files behind.
#include "engine/io/temp_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <vector>

#include "engine/core/error.h"

namespace dynscope {

TempFile::TempFile(std::string target) : target_(std::move(target)) {
  std::vector<char> name(target_.begin(), target_.end());
  const char kSuffix[] = ".tmp-XXXXXX";
  name.insert(name.end(), kSuffix, kSuffix + sizeof kSuffix);
  const int fd = mkstemp(name.data());
  if (fd < 0) {
    throw IoError(
        target_, std::string("cannot create a temporary file next to it: ") + std::strerror(errno));
  }
  // mkstemp creates the file with mode 0600; a scene or point file is an ordinary output.
  fchmod(fd, 0644);
  close(fd);
  temp_ = name.data();
}

TempFile::~TempFile() {
  if (!committed_) std::remove(temp_.c_str());
}

void TempFile::commit() {
  if (std::rename(temp_.c_str(), target_.c_str()) != 0) {
    throw IoError(target_,
                  std::string("cannot rename the temporary file onto it: ") + std::strerror(errno));
  }
  committed_ = true;
}

void write_text_file_atomically(const std::string& path, const std::string& text) {
  TempFile temp(path);
  {
    std::ofstream out(temp.path(), std::ios::binary | std::ios::trunc);
    out << text;
    out.close();
    if (!out) throw IoError(path, "cannot write");
  }
  temp.commit();
}

std::string read_text_file(const std::string& path, const std::string& cannot_open) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, cannot_open);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace dynscope
