// Tests of the internal HDF5 helpers: typed round trips, conversions, shape/type errors.
#include "engine/io/h5_util.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "tests/io/io_test_util.h"

namespace dynscope::h5 {
namespace {

using test::error_of;
using test::expect_contains;

class H5UtilTest : public ::testing::Test {
 protected:
  test::TempDir dir_;
  std::string path_ = dir_.file("data.h5");
};

TEST_F(H5UtilTest, WritesAndReadsEveryType) {
  {
    Group root = Group::create_file(path_);
    const Group g = root.create_group("g");
    const double m[6] = {1.5, -2, 3, 4, 5, 6.25};
    g.write_matrix("m", m, 2, 3);
    const int32_t im[3] = {7, -8, 9};
    g.write_int_matrix("im", im, 1, 3);
    g.write_vector("v", {0.1, 0.2});
    g.write_int_vector("iv", {-1, 2, 3});
    g.write_uint8_vector("u8", {0, 1, 255});
    g.write_scalar("s", 2.5);
    g.write_int_scalar("is", -4);
    g.write_strings("names", {"a", "", "größe"});
    root.write_attribute("text", std::string("hello"));
    root.write_attribute("real", 0.125);
    root.write_attribute("int", int64_t{-3});
    root.write_attribute("big", uint64_t{0xFFFFFFFFFFFFFFFFULL});
    root.close();
  }
  const Group root = Group::open_file(path_);
  const Group g = root.group("g");
  EXPECT_EQ(g.path(), "g");
  EXPECT_EQ(g.child_path("m"), "g/m");
  MatrixXdR m(2, 3);
  m << 1.5, -2, 3, 4, 5, 6.25;
  EXPECT_EQ(g.read_matrix("m", 2, 3), m);
  EXPECT_EQ(g.read_matrix("m", -1, 3), m);
  EXPECT_EQ(g.read_int_matrix("im", -1, 3), (MatrixXlR(1, 3) << 7, -8, 9).finished());
  EXPECT_EQ(g.read_vector("v", 2), (std::vector<double>{0.1, 0.2}));
  EXPECT_EQ(g.read_int_vector("iv", -1), (std::vector<int64_t>{-1, 2, 3}));
  EXPECT_EQ(g.read_int_vector("u8", 3), (std::vector<int64_t>{0, 1, 255}));
  EXPECT_EQ(g.read_vector("iv", 3), (std::vector<double>{-1, 2, 3}));
  EXPECT_EQ(g.read_scalar("s"), 2.5);
  EXPECT_EQ(g.read_int_scalar("is"), -4);
  EXPECT_EQ(g.read_strings("names", 3), (std::vector<std::string>{"a", "", "größe"}));
  EXPECT_EQ(root.string_attribute("text"), "hello");
  EXPECT_EQ(root.double_attribute("real"), 0.125);
  EXPECT_EQ(root.double_attribute("int"), -3.0);
  EXPECT_EQ(root.int_attribute("int"), -3);
  EXPECT_EQ(root.uint_attribute("big"), 0xFFFFFFFFFFFFFFFFULL);
  EXPECT_FALSE(root.string_attribute("absent").has_value());
  EXPECT_EQ(g.shape("m").text(), "[2,3] float64");
  EXPECT_EQ(g.shape("u8").text(), "[3] uint8");
  EXPECT_EQ(g.shape("s").text(), "scalar float64");
  EXPECT_EQ(g.shape("names").text(), "[3] string");
  EXPECT_TRUE(root.has_group("g"));
  EXPECT_FALSE(root.has_dataset("g"));
  EXPECT_TRUE(g.has_dataset("m"));
  EXPECT_FALSE(g.has("zzz"));
  EXPECT_EQ(g.children(),
            (std::vector<std::string>{"im", "is", "iv", "m", "names", "s", "u8", "v"}));
}

TEST_F(H5UtilTest, ZeroSizedArraysRoundTrip) {
  {
    Group root = Group::create_file(path_);
    root.write_matrix("empty", nullptr, 0, 3);
    root.write_strings("none", {});
    root.close();
  }
  const Group root = Group::open_file(path_);
  EXPECT_EQ(root.read_matrix("empty", 0, 3).rows(), 0);
  EXPECT_TRUE(root.read_strings("none", 0).empty());
}

TEST_F(H5UtilTest, ShapeAndTypeErrorsNameFileAndDataset) {
  {
    Group root = Group::create_file(path_);
    const Group g = root.create_group("static");
    const double m[10] = {};
    g.write_matrix("positions", m, 5, 2);
    g.write_strings("names", {"x"});
    g.write_vector("pair", {1, 2});
    root.write_attribute("label", std::string("text"));
    root.write_attribute("negative", int64_t{-1});
    root.close();
  }
  const Group root = Group::open_file(path_);
  const Group g = root.group("static");
  expect_contains(error_of<FormatError>([&] { g.read_matrix("positions", -1, 3); }),
                  {path_ + ": static/positions: expected [N,3] numbers, got [5,2] float64"});
  expect_contains(error_of<FormatError>([&] { g.read_matrix("positions", 4, 2); }),
                  {"expected [4,2] numbers"});
  expect_contains(error_of<FormatError>([&] { g.read_vector("positions", -1); }),
                  {"expected [N] numbers, got [5,2]"});
  expect_contains(error_of<FormatError>([&] { g.read_int_vector("pair", 2); }),
                  {"static/pair", "expected [2] integers, got [2] float64"});
  expect_contains(error_of<FormatError>([&] { g.read_vector("names", 1); }),
                  {"static/names", "got [1] string"});
  expect_contains(error_of<FormatError>([&] { g.read_strings("pair", 2); }),
                  {"expected [2] strings"});
  expect_contains(error_of<FormatError>([&] { g.read_scalar("pair"); }),
                  {"static/pair", "single value", "[2]"});
  expect_contains(error_of<FormatError>([&] { g.read_matrix("nothing", -1, 3); }),
                  {path_ + ": static/nothing: missing dataset"});
  expect_contains(error_of<FormatError>([&] { root.read_matrix("static", -1, 3); }),
                  {"static: is not a dataset"});
  expect_contains(error_of<FormatError>([&] { g.group("positions"); }),
                  {"static/positions: is not a group"});
  expect_contains(error_of<FormatError>([&] { root.double_attribute("label"); }),
                  {"@label", "expected numbers"});
  expect_contains(error_of<FormatError>([&] { root.uint_attribute("negative"); }),
                  {"@negative", "negative"});
}

TEST_F(H5UtilTest, ReadsH5pyStyleBoolsAndFixedStrings) {
  Group::create_file(path_).close();
  test::h5_edit(path_, [](hid_t f) {
    const hid_t bool_type = H5Tenum_create(H5T_NATIVE_INT8);
    int8_t v = 0;
    H5Tenum_insert(bool_type, "FALSE", &v);
    v = 1;
    H5Tenum_insert(bool_type, "TRUE", &v);
    const hsize_t dims[1] = {3};
    const hid_t space = H5Screate_simple(1, dims, nullptr);
    const hid_t ds =
        H5Dcreate2(f, "flags", bool_type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    const int8_t flags[3] = {1, 0, 1};
    H5Dwrite(ds, bool_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, flags);
    H5Dclose(ds);
    const hid_t str = H5Tcopy(H5T_C_S1);
    H5Tset_size(str, 5);
    H5Tset_strpad(str, H5T_STR_SPACEPAD);
    const hid_t sds = H5Dcreate2(f, "padded", str, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(sds, str, H5S_ALL, H5S_ALL, H5P_DEFAULT, "ab   cdefgh    ");
    H5Dclose(sds);
    H5Tclose(str);
    H5Sclose(space);
    H5Tclose(bool_type);
  });
  const Group root = Group::open_file(path_);
  EXPECT_EQ(root.read_vector("flags", 3), (std::vector<double>{1, 0, 1}));
  EXPECT_EQ(root.read_int_vector("flags", 3), (std::vector<int64_t>{1, 0, 1}));
  EXPECT_EQ(root.shape("flags").text(), "[3] enum");
  EXPECT_EQ(root.read_strings("padded", 3), (std::vector<std::string>{"ab", "cdefg", "h"}));
}

TEST_F(H5UtilTest, SingleElementArraysCountAsScalars) {
  {
    Group root = Group::create_file(path_);
    root.write_vector("one", {4.0});
    root.write_int_vector("ione", {9});
    root.close();
  }
  const Group root = Group::open_file(path_);
  EXPECT_EQ(root.read_scalar("one"), 4.0);
  EXPECT_EQ(root.read_int_scalar("ione"), 9);
}

TEST_F(H5UtilTest, FailuresReportHdf5sReason) {
  silence_errors();
  EXPECT_LT(H5Fopen(dir_.file("absent.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), 0);
  EXPECT_FALSE(take_error().empty());
  EXPECT_TRUE(take_error().empty()) << "take_error clears the stack";
  Group root = Group::create_file(path_);
  root.write_vector("x", {1});
  expect_contains(error_of<IoError>([&] { root.write_vector("x", {2}); }),
                  {path_ + ": x: cannot create dataset (HDF5: "});
}

TEST_F(H5UtilTest, CreateInMissingDirectoryThrowsIoError) {
  const std::string bad = dir_.file("no/such/dir.h5");
  expect_contains(error_of<IoError>([&] { Group::create_file(bad); }), {bad, "cannot be created"});
}

TEST_F(H5UtilTest, ChildrenAreSortedWhateverTheCreationOrder) {
  std::vector<std::string> expected;
  {
    Group root = Group::create_file(path_);
    // Enough links for HDF5's dense (B-tree) storage, created out of name order.
    for (int i = 0; i < 300; ++i) {
      char name[16];
      std::snprintf(name, sizeof name, "%04d", (i * 7) % 300);
      root.create_group(name);
      expected.push_back(name);
    }
    root.close();
  }
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(Group::open_file(path_).children(), expected);
}

// A dataset whose header declares `dims` doubles, none of them written (so the file stays small).
void create_unwritten_dataset(const std::string& path, const std::vector<hsize_t>& dims,
                              bool deflate) {
  Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  Handle space(H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr));
  Handle dcpl(H5Pcreate(H5P_DATASET_CREATE));
  if (deflate) {
    std::vector<hsize_t> chunk(dims.size(), 1);
    chunk.back() = std::min<hsize_t>(dims.back(), 1024);
    H5Pset_chunk(dcpl.get(), static_cast<int>(chunk.size()), chunk.data());
    H5Pset_deflate(dcpl.get(), 6);
  }
  Handle ds(H5Dcreate2(file.get(), "big", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, dcpl.get(),
                       H5P_DEFAULT));
  ASSERT_TRUE(ds.valid());
}

TEST_F(H5UtilTest, DeclaredSizesBeyondTheFileAreRefusedBeforeAllocating) {
  create_unwritten_dataset(path_, {1000000000, 3}, false);  // 24 GB declared, a few KB on disk
  expect_contains(error_of<FormatError>([&] { Group::open_file(path_).read_matrix("big", -1, 3); }),
                  {path_, "big", "[1000000000,3] float64", "more than the file"});
  // Compressed data may expand, but not past deflate's best ratio.
  create_unwritten_dataset(path_, {400000000}, true);
  expect_contains(error_of<FormatError>([&] { Group::open_file(path_).read_vector("big", -1); }),
                  {path_, "big", "more than the file"});
}

TEST(H5Handle, ClosesOnceAndMoves) {
  Handle a(H5Screate(H5S_SCALAR));
  const hid_t id = a.get();
  EXPECT_GT(H5Iis_valid(id), 0);
  Handle b(std::move(a));
  EXPECT_FALSE(a.valid());
  EXPECT_EQ(b.get(), id);
  EXPECT_TRUE(b.reset());
  EXPECT_LE(H5Iis_valid(id), 0);
  EXPECT_TRUE(b.reset()) << "resetting an empty handle is a no-op";
}

}  // namespace
}  // namespace dynscope::h5
