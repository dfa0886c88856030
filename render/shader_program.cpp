// ShaderProgram: compile/link through GlFunctions; errors name the shader file and line.
#include "render/shader_program.h"

#include <regex>
#include <sstream>
#include <utility>

#include "engine/core/error.h"
#include "render/embedded_shaders.h"

namespace dynscope::render {
namespace {

std::string shader_log(const GlFunctions& gl, GLuint shader) {
  GLint length = 0;
  gl.GetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
  gl.GetShaderInfoLog(shader, length, nullptr, log.data());
  return log.c_str();
}

std::string program_log(const GlFunctions& gl, GLuint program) {
  GLint length = 0;
  gl.GetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
  std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
  gl.GetProgramInfoLog(program, length, nullptr, log.data());
  return log.c_str();
}

GLuint compile(const GlFunctions& gl, GLenum type, const std::string& name,
               const std::string& source) {
  const GLuint shader = gl.CreateShader(type);
  if (!shader) throw Error("shaders/" + name + ": glCreateShader failed");
  const char* text = source.c_str();
  gl.ShaderSource(shader, 1, &text, nullptr);
  gl.CompileShader(shader);
  GLint ok = GL_FALSE;
  gl.GetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    const std::string log = shader_log(gl, shader);
    gl.DeleteShader(shader);
    throw Error("shader compile failed:\n" + format_shader_log("shaders/" + name, log));
  }
  return shader;
}

}  // namespace

const char* embedded_shader_source(const std::string& name) {
  std::string known;
  for (const EmbeddedShader& s : embedded_shaders()) {
    if (name == s.name) return s.source;
    known += known.empty() ? s.name : std::string(", ") + s.name;
  }
  throw ValueError("shader", "'" + name + "' is not embedded (known: " + known + ")");
}

const std::vector<ProgramSources>& renderer_programs() {
  static const std::vector<ProgramSources> kPrograms = {
      {"points", "points.vert", "points.frag"}, {"pick", "points.vert", "pick.frag"},
      {"mesh", "mesh.vert", "mesh.frag"},       {"lines", "lines.vert", "lines.frag"},
      {"boxes", "box.vert", "lines.frag"},      {"grid", "grid.vert", "grid.frag"},
      {"discs", "discs.vert", "discs.frag"},    {"pick_discs", "discs.vert", "pick_discs.frag"},
  };
  return kPrograms;
}

const std::vector<ProgramSources>& embedded_programs() {
  static const std::vector<ProgramSources> kPrograms = [] {
    std::vector<ProgramSources> all = renderer_programs();
    all.push_back({"imgui", "imgui.vert", "imgui.frag"});
    return all;
  }();
  return kPrograms;
}

std::string format_shader_log(const std::string& file, const std::string& log) {
  // Mesa: "0:12(5): error: ...", NVIDIA: "0(12) : error ...", others: "ERROR: 0:12: ...".
  static const std::regex kMesa(R"(^\s*\d+:(\d+)\(\d+\):\s*(.*)$)");
  static const std::regex kNvidia(R"(^\s*\d+\((\d+)\)\s*:\s*(.*)$)");
  static const std::regex kOther(R"(^\s*(ERROR|WARNING):\s*\d+:(\d+):\s*(.*)$)");
  std::istringstream in(log);
  std::ostringstream out;
  std::string line;
  bool any = false;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::smatch m;
    if (std::regex_match(line, m, kMesa) || std::regex_match(line, m, kNvidia)) {
      out << (any ? "\n" : "") << file << ":" << m[1] << ": " << m[2];
    } else if (std::regex_match(line, m, kOther)) {
      out << (any ? "\n" : "") << file << ":" << m[2] << ": " << m[1] << ": " << m[3];
    } else {
      out << (any ? "\n" : "") << file << ": " << line;
    }
    any = true;
  }
  if (!any) out << file << ": (the driver gave no log)";
  return out.str();
}

ShaderProgram ShaderProgram::from_embedded(const GlFunctions& gl, const std::string& vertex_file,
                                           const std::string& fragment_file) {
  return from_sources(gl, vertex_file, embedded_shader_source(vertex_file), fragment_file,
                      embedded_shader_source(fragment_file));
}

ShaderProgram ShaderProgram::from_sources(const GlFunctions& gl, const std::string& vertex_name,
                                          const std::string& vertex_source,
                                          const std::string& fragment_name,
                                          const std::string& fragment_source) {
  const GLuint vs = compile(gl, GL_VERTEX_SHADER, vertex_name, vertex_source);
  GLuint fs = 0;
  try {
    fs = compile(gl, GL_FRAGMENT_SHADER, fragment_name, fragment_source);
  } catch (...) {
    gl.DeleteShader(vs);
    throw;
  }
  ShaderProgram program;
  program.gl_ = &gl;
  program.id_ = gl.CreateProgram();
  gl.AttachShader(program.id_, vs);
  gl.AttachShader(program.id_, fs);
  gl.LinkProgram(program.id_);
  gl.DeleteShader(vs);
  gl.DeleteShader(fs);
  GLint ok = GL_FALSE;
  gl.GetProgramiv(program.id_, GL_LINK_STATUS, &ok);
  if (!ok) {
    throw Error("shader link failed for shaders/" + vertex_name + " + shaders/" + fragment_name +
                ":\n" + program_log(gl, program.id_));
  }
  return program;
}

ShaderProgram::~ShaderProgram() {
  if (id_ && gl_) gl_->DeleteProgram(id_);
}

ShaderProgram::ShaderProgram(ShaderProgram&& other) noexcept
    : gl_(other.gl_), id_(std::exchange(other.id_, 0)), locations_(std::move(other.locations_)) {}

ShaderProgram& ShaderProgram::operator=(ShaderProgram&& other) noexcept {
  if (this != &other) {
    if (id_ && gl_) gl_->DeleteProgram(id_);
    gl_ = other.gl_;
    id_ = std::exchange(other.id_, 0);
    locations_ = std::move(other.locations_);
  }
  return *this;
}

void ShaderProgram::use() const { gl_->UseProgram(id_); }

GLint ShaderProgram::uniform(const char* name) const {
  auto it = locations_.find(name);
  if (it != locations_.end()) return it->second;
  const GLint location = gl_->GetUniformLocation(id_, name);
  locations_.emplace(name, location);
  return location;
}

void ShaderProgram::set(const char* name, int value) const { gl_->Uniform1i(uniform(name), value); }
void ShaderProgram::set(const char* name, float value) const {
  gl_->Uniform1f(uniform(name), value);
}
void ShaderProgram::set(const char* name, float x, float y) const {
  gl_->Uniform2f(uniform(name), x, y);
}
void ShaderProgram::set(const char* name, float x, float y, float z) const {
  gl_->Uniform3f(uniform(name), x, y, z);
}
void ShaderProgram::set_matrix(const char* name, const float* column_major) const {
  gl_->UniformMatrix4fv(uniform(name), 1, GL_FALSE, column_major);
}

}  // namespace dynscope::render
