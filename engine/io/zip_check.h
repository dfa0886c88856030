// Integrity check of zip archives (LibTorch checkpoints): every member's CRC-32 against its data.
#pragma once

#include <cstdint>
#include <string>

namespace dynscope {

/// CRC-32 (IEEE 802.3, the zip and PNG polynomial) of `size` bytes, continuing from `crc`
/// (0 to start).
uint32_t crc32(const void* data, size_t size, uint32_t crc = 0);

/// Reads the zip archive at `path` and checks its structure (end record, central directory,
/// local headers agreeing with it, every member inside the file, stored or deflated) and the
/// CRC-32 of every member's (inflated) data. Returns the number of members. Throws IoError if
/// the file cannot be read, FormatError naming the member whose data or header is corrupt.
int64_t verify_zip_archive(const std::string& path);

}  // namespace dynscope
