// Atomic file writes for every writer (write to a temporary file next to the target, then rename),
// and the matching whole-file read.
#pragma once

#include <string>

namespace dynscope {

/// A fresh temporary file `target + ".tmp-XXXXXX"` in the target's directory (so the final
/// rename is atomic). It is removed on destruction unless commit() moved it onto the target,
/// so a failed write never leaves a partial file and never touches an existing target.
class TempFile {
 public:
  /// Creates the temporary file; throws IoError naming `target` if its directory is not writable.
  explicit TempFile(std::string target);
  ~TempFile();
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;

  /// Path of the temporary file to write.
  const std::string& path() const { return temp_; }
  /// Renames the temporary file onto the target; throws IoError naming the target on failure.
  void commit();

 private:
  std::string target_;
  std::string temp_;
  bool committed_ = false;
};

/// Writes `text` to `path` through a TempFile, so an existing file is replaced only by a complete
/// one. Throws IoError naming `path` if it cannot be written.
void write_text_file_atomically(const std::string& path, const std::string& text);

/// The whole content of `path`. Throws IoError(path, cannot_open) if it cannot be opened.
std::string read_text_file(const std::string& path, const std::string& cannot_open = "cannot open");

}  // namespace dynscope
