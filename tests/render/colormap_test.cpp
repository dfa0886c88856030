// Tests of the colormaps and the categorical palette.
#include "render/colormap.h"

#include <gtest/gtest.h>

#include "engine/core/error.h"

namespace dynscope::render {
namespace {

TEST(Colormap, MatchesReferenceValuesAndClamps) {
  EXPECT_TRUE(colormap("viridis", 0.0f).isApprox(Color(0.267004f, 0.004874f, 0.329415f), 1e-5f));
  EXPECT_TRUE(colormap("viridis", 0.5f).isApprox(Color(0.127568f, 0.566949f, 0.550556f), 1e-5f));
  EXPECT_TRUE(colormap("viridis", 2.0f).isApprox(Color(0.993248f, 0.906157f, 0.143936f), 1e-5f));
  EXPECT_TRUE(colormap("turbo", -1.0f).isApprox(Color(0.18995f, 0.07176f, 0.23217f), 1e-5f));
  EXPECT_TRUE(colormap("turbo", 1.0f).isApprox(Color(0.47960f, 0.01583f, 0.01055f), 1e-5f));
  // Turbo's middle is green-yellow, its ends dark blue and dark red.
  const Color mid = colormap("turbo", 0.5f);
  EXPECT_GT(mid.y(), mid.z());
}

TEST(Colormap, TableHas256OpaqueEntries) {
  const std::vector<uint8_t> t = colormap_table("turbo");
  ASSERT_EQ(t.size(), 1024u);
  for (size_t i = 3; i < t.size(); i += 4) EXPECT_EQ(t[i], 255);
  EXPECT_EQ(t[0], 48);  // 0.18995 * 255 rounded
}

TEST(Colormap, UnknownNameIsAValueErrorListingValidNames) {
  try {
    colormap("jet", 0.5f);
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("viridis"), std::string::npos);
  }
  EXPECT_THROW(colormap_table("jet"), ValueError);
}

TEST(Colormap, CategoricalColoursAreDistinctForThirtyIds) {
  for (int a = 0; a < 30; ++a) {
    for (int b = a + 1; b < 30; ++b) {
      EXPECT_GT((categorical_color(a) - categorical_color(b)).norm(), 0.02f) << a << " " << b;
    }
  }
  EXPECT_TRUE(categorical_color(3).isApprox(categorical_color(3)));
}

}  // namespace
}  // namespace dynscope::render
