// Tests of shader embedding, compilation, linking and error messages.
#include "render/shader_program.h"

#include <gtest/gtest.h>

#include <set>

#include "engine/core/error.h"
#include "render/embedded_shaders.h"
#include "render_test_util.h"

namespace dynscope::render {
namespace {

TEST(ShaderProgram, EveryEmbeddedProgramCompilesAndLinks) {
  GlContext& context = testing::osmesa(16, 16);
  GlFunctions gl;
  gl.load(context);
  for (const ProgramSources& p : embedded_programs()) {
    SCOPED_TRACE(p.name);
    ShaderProgram program = ShaderProgram::from_embedded(gl, p.vertex, p.fragment);
    EXPECT_NE(program.id(), 0u);
  }
}

TEST(ShaderProgram, EveryEmbeddedShaderIsUsedAndVersioned) {
  std::set<std::string> used;
  for (const ProgramSources& p : embedded_programs()) {
    used.insert(p.vertex);
    used.insert(p.fragment);
  }
  ASSERT_FALSE(embedded_shaders().empty());
  for (const EmbeddedShader& s : embedded_shaders()) {
    EXPECT_TRUE(used.count(s.name)) << s.name << " is embedded but no program uses it";
    EXPECT_EQ(std::string(s.source).rfind("#version 330 core", 0), 0u) << s.name;
  }
  EXPECT_THROW(embedded_shader_source("missing.frag"), ValueError);
}

TEST(ShaderProgram, CompileErrorNamesFileAndLine) {
  GlContext& context = testing::osmesa(16, 16);
  GlFunctions gl;
  gl.load(context);
  const std::string vs = embedded_shader_source("lines.vert");
  const std::string broken =
      "#version 330 core\nout vec4 o;\nvoid main() {\n  o = vec4(undefined_name);\n}\n";
  try {
    ShaderProgram::from_sources(gl, "lines.vert", vs, "broken.frag", broken);
    FAIL() << "expected a compile error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("shaders/broken.frag:4:"), std::string::npos) << e.what();
  }
}

TEST(ShaderProgram, LinkErrorNamesBothFiles) {
  GlContext& context = testing::osmesa(16, 16);
  GlFunctions gl;
  gl.load(context);
  const std::string vs = "#version 330 core\nvoid main() { gl_Position = vec4(0.0); }\n";
  const std::string fs =
      "#version 330 core\nvoid helper();\nout vec4 o;\nvoid main() { helper(); o = vec4(1.0); }\n";
  try {
    ShaderProgram::from_sources(gl, "a.vert", vs, "b.frag", fs);
    FAIL() << "expected a link error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("shaders/a.vert"), std::string::npos) << what;
    EXPECT_NE(what.find("shaders/b.frag"), std::string::npos) << what;
  }
}

TEST(ShaderProgram, FormatsDriverLogsOfSeveralVendors) {
  EXPECT_EQ(format_shader_log("shaders/x.frag", "0:12(5): error: `foo' undeclared\n"),
            "shaders/x.frag:12: error: `foo' undeclared");
  EXPECT_EQ(format_shader_log("shaders/x.frag", "0(7) : error C1008: undefined variable"),
            "shaders/x.frag:7: error C1008: undefined variable");
  EXPECT_EQ(format_shader_log("shaders/x.frag", "ERROR: 0:3: 'x' : undeclared identifier"),
            "shaders/x.frag:3: ERROR: 'x' : undeclared identifier");
  EXPECT_EQ(format_shader_log("shaders/x.frag", ""), "shaders/x.frag: (the driver gave no log)");
}

}  // namespace
}  // namespace dynscope::render
