// Tests of TempFile: commit replaces the target, abandoning it leaves the target untouched.
#include "engine/io/temp_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "tests/io/io_test_util.h"

namespace dynscope {
namespace {

std::string read_all(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(TempFile, CommitReplacesTheTarget) {
  test::TempDir dir;
  const std::string target = dir.file("out.txt");
  test::write_text(target, "old");
  TempFile temp(target);
  EXPECT_EQ(std::filesystem::path(temp.path()).parent_path(),
            std::filesystem::path(target).parent_path());
  EXPECT_EQ(temp.path().rfind(target + ".tmp-", 0), 0u) << temp.path();
  test::write_text(temp.path(), "new");
  EXPECT_EQ(read_all(target), "old") << "the target is untouched until commit";
  temp.commit();
  EXPECT_EQ(read_all(target), "new");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(TempFile, AbandonedTemporaryFileIsRemoved) {
  test::TempDir dir;
  const std::string target = dir.file("out.txt");
  test::write_text(target, "old");
  {
    TempFile temp(target);
    test::write_text(temp.path(), "partial");
  }
  EXPECT_EQ(read_all(target), "old");
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"out.txt"});
}

TEST(TempFile, TwoWritersGetDistinctFiles) {
  test::TempDir dir;
  TempFile a(dir.file("x"));
  TempFile b(dir.file("x"));
  EXPECT_NE(a.path(), b.path());
}

TEST(TempFile, MissingDirectoryIsAnIoErrorNamingTheTarget) {
  test::TempDir dir;
  const std::string target = dir.file("missing/out.txt");
  test::expect_contains(test::error_of<IoError>([&] { TempFile temp(target); }),
                        {target, "temporary file"});
}

}  // namespace
}  // namespace dynscope
