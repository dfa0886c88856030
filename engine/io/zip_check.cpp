// Zip structure and CRC-32 verification (APPNOTE.TXT layout; zip64 records included).
#include "engine/io/zip_check.h"

#include <zlib.h>

#include <array>
#include <cstring>
#include <fstream>
#include <vector>

#include "engine/core/error.h"

namespace dynscope {
namespace {

constexpr uint32_t kEndSignature = 0x06054b50;
constexpr uint32_t kEnd64Signature = 0x06064b50;
constexpr uint32_t kEnd64LocatorSignature = 0x07064b50;
constexpr uint32_t kCentralSignature = 0x02014b50;
constexpr uint32_t kLocalSignature = 0x04034b50;
constexpr uint32_t kSaturated32 = 0xffffffffu;
// The end record is 22 bytes plus a comment of at most 65535.
constexpr size_t kMaxEndSearch = 22 + 65535;

const std::array<uint32_t, 256>& crc_table() {
  static const std::array<uint32_t, 256> table = [] {
    std::array<uint32_t, 256> t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  return table;
}

// Little-endian fields of a byte buffer, bounds-checked by the caller.
uint64_t le(const unsigned char* p, int bytes) {
  uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = (v << 8) | p[i];
  return v;
}

class Reader {
 public:
  explicit Reader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw IoError(path, "cannot be opened for reading");
    in_.seekg(0, std::ios::end);
    size_ = static_cast<uint64_t>(in_.tellg());
  }
  uint64_t size() const { return size_; }
  // `n` bytes at `offset`; throws FormatError(`what`) if they are not all inside the file.
  std::vector<unsigned char> read(uint64_t offset, uint64_t n, const std::string& what) {
    if (offset > size_ || n > size_ - offset) {
      throw FormatError(path_, what, "lies outside the file (truncated or corrupt archive)");
    }
    std::vector<unsigned char> buf(n);
    in_.seekg(static_cast<std::streamoff>(offset));
    in_.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(n));
    if (static_cast<uint64_t>(in_.gcount()) != n) throw IoError(path_, "read failed");
    return buf;
  }
  // CRC-32 of `n` stored bytes at `offset`, read in blocks.
  uint32_t crc(uint64_t offset, uint64_t n, const std::string& what) {
    check_range(offset, n, what);
    in_.seekg(static_cast<std::streamoff>(offset));
    std::vector<char> buf(1 << 16);
    uint32_t c = 0;
    while (n > 0) {
      const auto chunk = static_cast<std::streamsize>(std::min<uint64_t>(n, buf.size()));
      in_.read(buf.data(), chunk);
      if (in_.gcount() != chunk) throw IoError(path_, "read failed");
      c = crc32(buf.data(), static_cast<size_t>(chunk), c);
      n -= static_cast<uint64_t>(chunk);
    }
    return c;
  }
  // CRC-32 of the `n` bytes that inflating the raw deflate stream of `compressed` bytes at
  // `offset` gives; throws FormatError(`what`) if the stream is corrupt or inflates to another
  // size. Streams in blocks: nothing of the member's size is allocated.
  uint32_t inflated_crc(uint64_t offset, uint64_t compressed, uint64_t n, const std::string& what) {
    check_range(offset, compressed, what);
    in_.seekg(static_cast<std::streamoff>(offset));
    z_stream z{};
    if (inflateInit2(&z, -MAX_WBITS) != Z_OK) throw IoError(path_, "cannot start inflating");
    std::vector<unsigned char> in(1 << 16), out(1 << 16);
    uint32_t c = 0;
    uint64_t produced = 0;
    int status = Z_OK;
    while (status != Z_STREAM_END) {
      if (z.avail_in == 0 && compressed > 0) {
        const auto chunk = static_cast<std::streamsize>(std::min<uint64_t>(compressed, in.size()));
        in_.read(reinterpret_cast<char*>(in.data()), chunk);
        z.next_in = in.data();
        z.avail_in = static_cast<uInt>(chunk);
        compressed -= static_cast<uint64_t>(chunk);
      }
      z.next_out = out.data();
      z.avail_out = static_cast<uInt>(out.size());
      status = inflate(&z, Z_NO_FLUSH);
      const size_t got = out.size() - z.avail_out;
      produced += got;
      c = crc32(out.data(), got, c);
      const bool stuck = status == Z_BUF_ERROR && z.avail_in == 0 && compressed == 0;
      if ((status != Z_OK && status != Z_STREAM_END && status != Z_BUF_ERROR) || stuck ||
          produced > n) {
        inflateEnd(&z);
        throw FormatError(path_, what, "compressed data is corrupt");
      }
    }
    inflateEnd(&z);
    if (produced != n) throw FormatError(path_, what, "inflates to another size than declared");
    return c;
  }

 private:
  void check_range(uint64_t offset, uint64_t n, const std::string& what) const {
    if (offset > size_ || n > size_ - offset) {
      throw FormatError(path_, what, "data lies outside the file (truncated or corrupt archive)");
    }
  }

 public:
 private:
  std::string path_;
  std::ifstream in_;
  uint64_t size_ = 0;
};

struct Directory {
  uint64_t entries = 0;
  uint64_t offset = 0;
  uint64_t size = 0;
};

Directory find_directory(Reader& r, const std::string& path) {
  const uint64_t tail = std::min<uint64_t>(r.size(), kMaxEndSearch);
  if (tail < 22) throw FormatError(path, "zip", "too short for a zip archive");
  const std::vector<unsigned char> buf = r.read(r.size() - tail, tail, "zip end record");
  for (uint64_t i = tail - 22 + 1; i-- > 0;) {
    const unsigned char* p = buf.data() + i;
    if (le(p, 4) != kEndSignature) continue;
    Directory d{le(p + 10, 2), le(p + 16, 4), le(p + 12, 4)};
    const uint64_t end_offset = r.size() - tail + i;
    // Zip64: the locator (20 bytes) just before the end record points at the zip64 end record.
    if ((d.entries == 0xffff || d.offset == kSaturated32 || d.size == kSaturated32) &&
        end_offset >= 20) {
      const std::vector<unsigned char> loc = r.read(end_offset - 20, 20, "zip64 locator");
      if (le(loc.data(), 4) == kEnd64LocatorSignature) {
        const std::vector<unsigned char> e64 =
            r.read(le(loc.data() + 8, 8), 56, "zip64 end record");
        if (le(e64.data(), 4) != kEnd64Signature) {
          throw FormatError(path, "zip64 end record", "bad signature");
        }
        d = {le(e64.data() + 32, 8), le(e64.data() + 48, 8), le(e64.data() + 40, 8)};
      }
    }
    return d;
  }
  throw FormatError(path, "zip",
                    "no end-of-central-directory record (not a zip archive, or "
                    "truncated)");
}

}  // namespace

uint32_t crc32(const void* data, size_t size, uint32_t crc) {
  const auto& table = crc_table();
  const auto* p = static_cast<const unsigned char*>(data);
  uint32_t c = crc ^ 0xffffffffu;
  for (size_t i = 0; i < size; ++i) c = table[(c ^ p[i]) & 0xff] ^ (c >> 8);
  return c ^ 0xffffffffu;
}

int64_t verify_zip_archive(const std::string& path) {
  Reader r(path);
  const Directory d = find_directory(r, path);
  // Each central entry takes at least 46 bytes: a count beyond that is corrupt.
  if (d.size > r.size() || d.entries > d.size / 46) {
    throw FormatError(path, "zip central directory",
                      "declares " + std::to_string(d.entries) + " members in " +
                          std::to_string(d.size) + " bytes (corrupt archive)");
  }
  const std::vector<unsigned char> dir = r.read(d.offset, d.size, "zip central directory");
  uint64_t pos = 0;
  for (uint64_t e = 0; e < d.entries; ++e) {
    const std::string entry = "zip member " + std::to_string(e);
    if (pos + 46 > dir.size() || le(dir.data() + pos, 4) != kCentralSignature) {
      throw FormatError(path, entry, "bad central directory entry");
    }
    const unsigned char* c = dir.data() + pos;
    const uint64_t method = le(c + 10, 2);
    const auto expected_crc = static_cast<uint32_t>(le(c + 16, 4));
    uint64_t compressed = le(c + 20, 4);
    uint64_t uncompressed = le(c + 24, 4);
    const uint64_t name_len = le(c + 28, 2), extra_len = le(c + 30, 2), comment_len = le(c + 32, 2);
    uint64_t local = le(c + 42, 4);
    if (pos + 46 + name_len + extra_len + comment_len > dir.size()) {
      throw FormatError(path, entry, "central directory entry runs past the directory");
    }
    const std::string name(reinterpret_cast<const char*>(c + 46), name_len);
    const std::string member = "zip member '" + name + "'";
    // Zip64 extended information: the saturated fields, in this order.
    const unsigned char* extra = c + 46 + name_len;
    for (uint64_t x = 0; x + 4 <= extra_len;) {
      const uint64_t id = le(extra + x, 2), len = le(extra + x + 2, 2);
      if (x + 4 + len > extra_len) break;
      if (id == 0x0001) {
        uint64_t field = x + 4;
        for (uint64_t* v : {&uncompressed, &compressed, &local}) {
          if (*v == kSaturated32 && field + 8 <= x + 4 + len) {
            *v = le(extra + field, 8);
            field += 8;
          }
        }
      }
      x += 4 + len;
    }
    if (method != 0 && method != 8) {
      throw FormatError(path, member,
                        "uses compression method " + std::to_string(method) +
                            " (only stored and deflated members are read)");
    }
    if (method == 0 && compressed != uncompressed) {
      throw FormatError(path, member, "stored sizes disagree (corrupt archive)");
    }
    const std::vector<unsigned char> header = r.read(local, 30, member + " local header");
    if (le(header.data(), 4) != kLocalSignature) {
      throw FormatError(path, member, "bad local header signature (corrupt archive)");
    }
    const uint64_t local_name_len = le(header.data() + 26, 2);
    const uint64_t local_extra_len = le(header.data() + 28, 2);
    const std::vector<unsigned char> local_name =
        r.read(local + 30, local_name_len, member + " local name");
    if (std::string(local_name.begin(), local_name.end()) != name) {
      throw FormatError(path, member, "local header names another member (corrupt archive)");
    }
    const uint64_t data = local + 30 + local_name_len + local_extra_len;
    const uint32_t actual = method == 0 ? r.crc(data, uncompressed, member)
                                        : r.inflated_crc(data, compressed, uncompressed, member);
    if (actual != expected_crc) {
      throw FormatError(path, member, "CRC-32 mismatch: its data is corrupt");
    }
    pos += 46 + name_len + extra_len + comment_len;
  }
  return static_cast<int64_t>(d.entries);
}

}  // namespace dynscope
