// Tests of the GL contexts and the GL function table (OSMesa; GLFW must fail cleanly headless).
#include <gtest/gtest.h>

#include <cstdlib>

#include "engine/core/error.h"
#include "render/context_factory.h"
#include "render/gl_functions.h"
#include "render_test_util.h"

namespace dynscope::render {
namespace {

TEST(GlContext, OsMesaGivesCoreProfileAndLoadsEveryEntryPoint) {
  GlContext& context = testing::osmesa(64, 32);
  EXPECT_EQ(context.backend(), "osmesa");
  GlFunctions gl;
  gl.load(context);
  GLint major = 0, profile = 0;
  gl.GetIntegerv(GL_MAJOR_VERSION, &major);
  gl.GetIntegerv(GL_CONTEXT_PROFILE_MASK, &profile);
  EXPECT_GE(major, 3);
  EXPECT_TRUE(profile & GL_CONTEXT_CORE_PROFILE_BIT);
#define DYNSCOPE_EXPECT_LOADED(upper, name) EXPECT_NE(gl.name, nullptr) << "gl" #name;
  DYNSCOPE_GL_FUNCTIONS(DYNSCOPE_EXPECT_LOADED)
#undef DYNSCOPE_EXPECT_LOADED
}

TEST(GlContext, ReadPixelsReturnsClearColourAtTheContextSize) {
  GlContext& context = testing::osmesa(48, 20);
  GlFunctions gl;
  gl.load(context);
  gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
  gl.Viewport(0, 0, 48, 20);
  gl.ClearColor(1.0f, 0.0f, 0.0f, 1.0f);
  gl.Clear(GL_COLOR_BUFFER_BIT);
  Image image = context.read_pixels();
  ASSERT_EQ(image.width, 48);
  ASSERT_EQ(image.height, 20);
  EXPECT_EQ(image.pixel(0, 0)[0], 255);
  EXPECT_EQ(image.pixel(47, 19)[1], 0);
  context.resize(30, 10);
  EXPECT_EQ(context.read_pixels().width, 30);
  EXPECT_THROW(context.resize(0, 10), ValueError);
}

TEST(GlContext, GlfwWithoutDisplayThrowsAClearError) {
  // CI has no display; force that here so the test means the same everywhere.
  ::unsetenv("DISPLAY");
  ::unsetenv("WAYLAND_DISPLAY");
  try {
    create_context("glfw", 64, 64);
    FAIL() << "expected dynscope::Error";
  } catch (const ValueError&) {
    FAIL() << "wrong exception type";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("glfw"), std::string::npos) << e.what();
  }
}

TEST(GlContext, UnknownBackendIsAValueError) {
  try {
    create_context("vulkan", 8, 8);
    FAIL();
  } catch (const ValueError& e) {
    EXPECT_NE(std::string(e.what()).find("vulkan"), std::string::npos);
  }
}

TEST(GlFunctions, CheckReportsAndDrainsGlErrors) {
  GlContext& context = testing::osmesa(16, 16);
  GlFunctions gl;
  gl.load(context);
  gl.check("clean state");
  gl.Enable(0xFFFF);  // not a capability: GL_INVALID_ENUM
  EXPECT_THROW(gl.check("bad enable"), Error);
  EXPECT_NO_THROW(gl.check("after draining"));
}

}  // namespace
}  // namespace dynscope::render
