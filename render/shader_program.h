// ShaderProgram: compiles and links a vertex + fragment shader pair, with readable errors.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "render/gl_functions.h"

namespace dynscope::render {

/// The programs the renderer uses, as (name, vertex file, fragment file) in shaders/.
struct ProgramSources {
  const char* name;
  const char* vertex;
  const char* fragment;
};
/// points, pick, mesh, lines, boxes and grid.
const std::vector<ProgramSources>& renderer_programs();
/// Every program the embedded shaders make: the renderer's plus the UI overlay ("imgui").
const std::vector<ProgramSources>& embedded_programs();

/// A linked GL program. Owns the GL object; needs its context current for every call.
class ShaderProgram {
 public:
  /// Compiles embedded shaders `vertex_file` and `fragment_file` (names in shaders/) and links
  /// them. Throws Error naming the shader file and line reported by the driver.
  static ShaderProgram from_embedded(const GlFunctions& gl, const std::string& vertex_file,
                                     const std::string& fragment_file);
  /// Same from source text; `vertex_name` / `fragment_name` are used in error messages.
  static ShaderProgram from_sources(const GlFunctions& gl, const std::string& vertex_name,
                                    const std::string& vertex_source,
                                    const std::string& fragment_name,
                                    const std::string& fragment_source);

  ShaderProgram() = default;
  ~ShaderProgram();
  ShaderProgram(ShaderProgram&& other) noexcept;
  ShaderProgram& operator=(ShaderProgram&& other) noexcept;
  ShaderProgram(const ShaderProgram&) = delete;
  ShaderProgram& operator=(const ShaderProgram&) = delete;

  GLuint id() const { return id_; }
  void use() const;
  /// Uniform location (cached; -1 for a uniform the driver optimised away, which GL ignores).
  GLint uniform(const char* name) const;
  void set(const char* name, int value) const;
  void set(const char* name, float value) const;
  void set(const char* name, float x, float y) const;
  void set(const char* name, float x, float y, float z) const;
  /// Column-major 4x4 matrix (Eigen's default storage).
  void set_matrix(const char* name, const float* column_major) const;

 private:
  const GlFunctions* gl_ = nullptr;
  GLuint id_ = 0;
  mutable std::map<std::string, GLint> locations_;
};

/// Turns a driver info log into "file:line: message" lines (Mesa "0:12(5): error: ...",
/// NVIDIA "0(12) : error ...", AMD/Intel "ERROR: 0:12: ..."); lines without a position keep
/// the file name only. Exposed for tests.
std::string format_shader_log(const std::string& file, const std::string& log);

}  // namespace dynscope::render
