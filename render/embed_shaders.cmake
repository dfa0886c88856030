# Embeds every GLSL file of SHADER_DIR into OUTPUT (a .cpp of string constants); run with cmake -P.
file(GLOB shader_files ${SHADER_DIR}/*.vert ${SHADER_DIR}/*.frag)
list(SORT shader_files)
set(body "")
foreach(f ${shader_files})
  get_filename_component(name ${f} NAME)
  file(READ ${f} content)
  if(content MATCHES "\\)dynscope_glsl\"")
    message(FATAL_ERROR "${f}: contains the raw-string delimiter )dynscope_glsl\"")
  endif()
  string(APPEND body "    {\"${name}\", R\"dynscope_glsl(${content})dynscope_glsl\"},\n")
endforeach()
set(text "// Generated from shaders/ by render/embed_shaders.cmake at build time; edit the .vert/.frag files.
#include \"render/embedded_shaders.h\"

namespace dynscope::render {

const std::vector<EmbeddedShader>& embedded_shaders() {
  static const std::vector<EmbeddedShader> kShaders = {
${body}  };
  return kShaders;
}

}  // namespace dynscope::render
")
# Rewrite only on change so an unchanged shader set does not trigger a recompile.
if(EXISTS ${OUTPUT})
  file(READ ${OUTPUT} old)
  if(old STREQUAL text)
    return()
  endif()
endif()
file(WRITE ${OUTPUT} "${text}")
