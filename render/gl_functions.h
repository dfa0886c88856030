// GlFunctions: the table of GL entry points the renderer uses, loaded from the current context.
#pragma once

#include <GL/glcorearb.h>

#include <string>

namespace dynscope::render {

class GlContext;

// X(UPPER, Name): the entry point glName with its <GL/glcorearb.h> type PFNGLUPPERPROC.
#define DYNSCOPE_GL_FUNCTIONS(X)                                    \
  X(ACTIVETEXTURE, ActiveTexture)                                   \
  X(ATTACHSHADER, AttachShader)                                     \
  X(BINDBUFFER, BindBuffer)                                         \
  X(BINDFRAMEBUFFER, BindFramebuffer)                               \
  X(BINDRENDERBUFFER, BindRenderbuffer)                             \
  X(BINDTEXTURE, BindTexture)                                       \
  X(BINDVERTEXARRAY, BindVertexArray)                               \
  X(BLENDFUNC, BlendFunc)                                           \
  X(BLENDFUNCSEPARATE, BlendFuncSeparate)                           \
  X(BLITFRAMEBUFFER, BlitFramebuffer)                               \
  X(BUFFERDATA, BufferData)                                         \
  X(CHECKFRAMEBUFFERSTATUS, CheckFramebufferStatus)                 \
  X(CLEAR, Clear)                                                   \
  X(CLEARCOLOR, ClearColor)                                         \
  X(CLEARDEPTH, ClearDepth)                                         \
  X(COLORMASK, ColorMask)                                           \
  X(COMPILESHADER, CompileShader)                                   \
  X(CREATEPROGRAM, CreateProgram)                                   \
  X(CREATESHADER, CreateShader)                                     \
  X(DELETEBUFFERS, DeleteBuffers)                                   \
  X(DELETEFRAMEBUFFERS, DeleteFramebuffers)                         \
  X(DELETEPROGRAM, DeleteProgram)                                   \
  X(DELETERENDERBUFFERS, DeleteRenderbuffers)                       \
  X(DELETESHADER, DeleteShader)                                     \
  X(DELETETEXTURES, DeleteTextures)                                 \
  X(DELETEVERTEXARRAYS, DeleteVertexArrays)                         \
  X(DEPTHFUNC, DepthFunc)                                           \
  X(DEPTHMASK, DepthMask)                                           \
  X(DISABLE, Disable)                                               \
  X(DISABLEVERTEXATTRIBARRAY, DisableVertexAttribArray)             \
  X(DRAWARRAYS, DrawArrays)                                         \
  X(DRAWARRAYSINSTANCED, DrawArraysInstanced)                       \
  X(DRAWELEMENTS, DrawElements)                                     \
  X(ENABLE, Enable)                                                 \
  X(ENABLEVERTEXATTRIBARRAY, EnableVertexAttribArray)               \
  X(FINISH, Finish)                                                 \
  X(FRAMEBUFFERRENDERBUFFER, FramebufferRenderbuffer)               \
  X(GENBUFFERS, GenBuffers)                                         \
  X(GENFRAMEBUFFERS, GenFramebuffers)                               \
  X(GENRENDERBUFFERS, GenRenderbuffers)                             \
  X(GENTEXTURES, GenTextures)                                       \
  X(GENVERTEXARRAYS, GenVertexArrays)                               \
  X(GETERROR, GetError)                                             \
  X(GETFLOATV, GetFloatv)                                           \
  X(GETINTEGERV, GetIntegerv)                                       \
  X(GETPROGRAMINFOLOG, GetProgramInfoLog)                           \
  X(GETPROGRAMIV, GetProgramiv)                                     \
  X(GETSHADERINFOLOG, GetShaderInfoLog)                             \
  X(GETSHADERIV, GetShaderiv)                                       \
  X(GETSTRING, GetString)                                           \
  X(GETUNIFORMLOCATION, GetUniformLocation)                         \
  X(LINEWIDTH, LineWidth)                                           \
  X(LINKPROGRAM, LinkProgram)                                       \
  X(PIXELSTOREI, PixelStorei)                                       \
  X(READBUFFER, ReadBuffer)                                         \
  X(READPIXELS, ReadPixels)                                         \
  X(RENDERBUFFERSTORAGE, RenderbufferStorage)                       \
  X(RENDERBUFFERSTORAGEMULTISAMPLE, RenderbufferStorageMultisample) \
  X(SCISSOR, Scissor)                                               \
  X(SHADERSOURCE, ShaderSource)                                     \
  X(TEXIMAGE2D, TexImage2D)                                         \
  X(TEXSUBIMAGE2D, TexSubImage2D)                                   \
  X(TEXPARAMETERI, TexParameteri)                                   \
  X(UNIFORM1F, Uniform1f)                                           \
  X(UNIFORM1I, Uniform1i)                                           \
  X(UNIFORM2F, Uniform2f)                                           \
  X(UNIFORM3F, Uniform3f)                                           \
  X(UNIFORMMATRIX4FV, UniformMatrix4fv)                             \
  X(USEPROGRAM, UseProgram)                                         \
  X(VERTEXATTRIB1F, VertexAttrib1f)                                 \
  X(VERTEXATTRIB3F, VertexAttrib3f)                                 \
  X(VERTEXATTRIBDIVISOR, VertexAttribDivisor)                       \
  X(VERTEXATTRIBPOINTER, VertexAttribPointer)                       \
  X(VIEWPORT, Viewport)

/// Every GL entry point the renderer calls, as members named without the "gl" prefix
/// (`gl.Clear(...)`). Calling GL only through this table keeps one binary correct with OSMesa
/// (which exports gl* symbols) and with GLFW (whose libGL is loaded at run time).
struct GlFunctions {
#define DYNSCOPE_GL_MEMBER(upper, name) PFNGL##upper##PROC name = nullptr;
  DYNSCOPE_GL_FUNCTIONS(DYNSCOPE_GL_MEMBER)
#undef DYNSCOPE_GL_MEMBER

  /// Loads every entry point through `context.get_proc_address` (the context must be current).
  /// Throws Error naming the first missing entry point and the backend.
  void load(GlContext& context);
  /// "GL 4.5 (Core Profile) Mesa 22.3.6 / llvmpipe ..." for logs and error messages.
  std::string describe() const;
  /// Throws Error("GL error 0x0502 after <what>") if glGetError reports one (and drains the queue).
  void check(const char* what) const;
};

}  // namespace dynscope::render
