// Tests of zip verification: the CRC-32 reference value, a shipped checkpoint passes, and a flipped
// bit in a member, a truncation or a foreign file are FormatErrors naming the archive.
#include "engine/io/zip_check.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "tests/io/io_test_util.h"

namespace dynscope {
namespace {

using test::error_of;
using test::expect_contains;

const std::string kCheckpoint =
    std::string(DYNSCOPE_SOURCE_DIR) + "/assets/models/movi-a_gnn_acc.pt";

std::string read_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

uint32_t le32(const std::string& s, size_t at) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = (v << 8) | static_cast<unsigned char>(s[at + i]);
  return v;
}

uint16_t le16(const std::string& s, size_t at) {
  return static_cast<uint16_t>(static_cast<unsigned char>(s[at]) |
                               (static_cast<unsigned char>(s[at + 1]) << 8));
}

TEST(ZipCheck, Crc32MatchesTheStandardCheckValue) {
  EXPECT_EQ(crc32("123456789", 9), 0xCBF43926u);
  EXPECT_EQ(crc32("", 0), 0u);
  // Continuing a CRC over two pieces equals one pass.
  EXPECT_EQ(crc32("6789", 4, crc32("12345", 5)), 0xCBF43926u);
}

TEST(ZipCheck, ShippedCheckpointVerifies) { EXPECT_GT(verify_zip_archive(kCheckpoint), 10); }

// (data offset, size) of every member with data, from the central directory (the local headers
// of LibTorch archives leave sizes to a trailing data descriptor).
std::vector<std::pair<size_t, size_t>> member_data(const std::string& zip) {
  const size_t end = zip.rfind("PK\x05\x06");
  const size_t entries = le16(zip, end + 10);
  size_t at = le32(zip, end + 16);
  std::vector<std::pair<size_t, size_t>> out;
  for (size_t e = 0; e < entries; ++e) {
    const size_t compressed = le32(zip, at + 20);
    const size_t local = le32(zip, at + 42);
    const size_t data = local + 30 + le16(zip, local + 26) + le16(zip, local + 28);
    if (compressed > 0) out.emplace_back(data, compressed);
    at += 46 + le16(zip, at + 28) + le16(zip, at + 30) + le16(zip, at + 32);
  }
  return out;
}

TEST(ZipCheck, FlippedBitInAnyMemberIsDetected) {
  test::TempDir dir;
  const std::string original = read_bytes(kCheckpoint);
  const auto members = member_data(original);
  ASSERT_GT(members.size(), 10u);
  // Every member, stored (weights) or deflated (code), at its first and middle byte (the last
  // byte of a deflate stream may hold only padding bits).
  int flipped = 0;
  for (const auto& [data, size] : members) {
    for (const size_t at : {data, data + size / 2}) {
      std::string bytes = original;
      bytes[at] = static_cast<char>(bytes[at] ^ 0x10);
      const std::string path = dir.file("flipped.pt");
      test::write_text(path, bytes);
      EXPECT_THROW(verify_zip_archive(path), FormatError) << "byte " << at;
      ++flipped;
    }
  }
  EXPECT_EQ(flipped, 2 * static_cast<int>(members.size()));
}

TEST(ZipCheck, TruncatedAndForeignFilesAreFormatErrors) {
  test::TempDir dir;
  const std::string original = read_bytes(kCheckpoint);
  const std::string truncated = dir.file("truncated.pt");
  test::write_text(truncated, original.substr(0, original.size() / 2));
  expect_contains(error_of<FormatError>([&] { verify_zip_archive(truncated); }), {truncated});
  const std::string text = dir.file("text.pt");
  test::write_text(text, "not an archive at all, just some words");
  expect_contains(error_of<FormatError>([&] { verify_zip_archive(text); }),
                  {text, "no end-of-central-directory record"});
}

}  // namespace
}  // namespace dynscope
