# Embeds GLSL files as C++ string constants (cmake -P, run at build time by unav_renderer's
# CMakeLists whenever a shader changes):
#   cmake -DOUT=<header> -DDIR=<shader folder> -DSHADERS=kName=file,... -P embed_glsl.cmake
# Each file becomes `inline constexpr const char* kName = R"GLSL(...)GLSL";` in namespace
# unav::renderer::detail. A line `#include "other.glsl"` is replaced by that file's text (GLSL
# has no includes); comments before a file's #version line are kept (the GLSL spec allows them).
set(_out "// Generated from ${DIR} by embed_glsl.cmake: edit the .glsl files, not this.\n#pragma once\n\nnamespace unav::renderer::detail {\n")
string(REPLACE "," ";" _pairs "${SHADERS}")
foreach(_pair IN LISTS _pairs)
  string(REPLACE "=" ";" _kv "${_pair}")
  list(GET _kv 0 _name)
  list(GET _kv 1 _file)
  file(READ "${DIR}/${_file}" _text)
  string(REGEX MATCHALL "#include \"[a-z_]+\\.glsl\"" _includes "${_text}")
  foreach(_inc IN LISTS _includes)
    string(REGEX REPLACE "#include \"([a-z_]+\\.glsl)\"" "\\1" _inc_file "${_inc}")
    file(READ "${DIR}/${_inc_file}" _inc_text)
    string(REPLACE "${_inc}" "${_inc_text}" _text "${_text}")
  endforeach()
  if(_text MATCHES "\\)GLSL\"")
    message(FATAL_ERROR "${DIR}/${_file}: contains the raw-string delimiter )GLSL\"")
  endif()
  string(APPEND _out "\ninline constexpr const char* ${_name} = R\"GLSL(${_text})GLSL\";\n")
endforeach()
string(APPEND _out "\n}  // namespace unav::renderer::detail\n")
# Written only when it changed: an unchanged header recompiles nothing.
if(EXISTS "${OUT}")
  file(READ "${OUT}" _old)
endif()
if(NOT _old STREQUAL _out)
  file(WRITE "${OUT}" "${_out}")
endif()
