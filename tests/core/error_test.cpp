// Tests that error messages name the file, field and value.
#include "engine/core/error.h"

#include <gtest/gtest.h>

namespace dynscope {
namespace {

TEST(ErrorTest, MessagesNameFileAndField) {
  const FormatError e("scene.h5", "static/mesh/vertices_0", "expected [N,3], got [5,2]");
  EXPECT_STREQ(e.what(), "scene.h5: static/mesh/vertices_0: expected [N,3], got [5,2]");
  EXPECT_EQ(e.path(), "scene.h5");
  EXPECT_EQ(e.field(), "static/mesh/vertices_0");
  const IoError& as_io = e;  // a FormatError is an IoError is an Error
  EXPECT_EQ(as_io.path(), "scene.h5");
  const ValueError v("--count", "must be positive, got -1");
  EXPECT_STREQ(v.what(), "--count: must be positive, got -1");
}

}  // namespace
}  // namespace dynscope
