# cmake -DROOT=<source dir> -P CheckHouse.cmake
#
# Checks the rules of the house (docs/architecture.md) that a compiler does not: every
# #include "layer/..." in a source file names a layer that the file's own layer may
# include; no source file under src/ is longer than 500 lines (one job each); and
# comments cite what a reader can open (docs/references.md), not a file outside the
# repository. Prints each breach and fails if there is one. Run by CTest as House.rules.

cmake_minimum_required(VERSION 3.25)

# A layer and the layers it may include besides itself (the table in docs/architecture.md).
set(_allowed_core "")
set(_allowed_patch core)
set(_allowed_scene core patch)
set(_allowed_tracker core patch)
set(_allowed_raster core)
set(_allowed_xscan core patch tracker raster)
set(_allowed_render core patch scene tracker raster xscan)
set(_allowed_mpi core patch scene tracker raster xscan render)
set(_allowed_cli core patch scene tracker raster xscan render mpi)
set(_layers core patch scene tracker raster xscan render mpi cli)
set(_library core patch scene tracker raster xscan render mpi)
# Folders outside src/ that use the library: never the program, never the tests.
set(_users bench fuzz examples)

if(NOT ROOT)
  message(FATAL_ERROR "usage: cmake -DROOT=<source dir> -P CheckHouse.cmake")
endif()

set(_bad 0)
file(GLOB_RECURSE _files RELATIVE "${ROOT}" "${ROOT}/src/*.h" "${ROOT}/src/*.cpp" "${ROOT}/src/*.in"
     "${ROOT}/bench/*.h" "${ROOT}/bench/*.cpp" "${ROOT}/fuzz/*.h" "${ROOT}/fuzz/*.cpp"
     "${ROOT}/examples/*.h" "${ROOT}/examples/*.cpp")
foreach(_file IN LISTS _files)
  string(REPLACE "/" ";" _parts "${_file}")
  list(GET _parts 0 _top)
  if(_top STREQUAL "src")
    list(GET _parts 1 _layer)
    if(NOT _layer IN_LIST _layers)
      message("${_file}: src/${_layer} is not a layer of docs/architecture.md")
      math(EXPR _bad "${_bad} + 1")
      continue()
    endif()
    set(_may ${_allowed_${_layer}} ${_layer})
  else()
    set(_layer "${_top}")
    set(_may ${_library})
  endif()
  file(STRINGS "${ROOT}/${_file}" _includes REGEX "^[ \t]*#[ \t]*include[ \t]+\"[a-z_]+/")
  foreach(_line IN LISTS _includes)
    string(REGEX REPLACE "^[ \t]*#[ \t]*include[ \t]+\"([a-z_]+)/.*" "\\1" _to "${_line}")
    if((_to IN_LIST _layers OR _to STREQUAL "tests") AND NOT _to IN_LIST _may)
      message("${_file}: includes ${_to}/ (${_layer} may not): ${_line}")
      math(EXPR _bad "${_bad} + 1")
    endif()
  endforeach()
endforeach()

# One job per file: a file that outgrows this has more than one.
set(_max_lines 500)
foreach(_file IN LISTS _files)
  if(NOT _file MATCHES "^src/")
    continue()
  endif()
  file(READ "${ROOT}/${_file}" _text)
  string(REGEX MATCHALL "\n" _newlines "${_text}")
  list(LENGTH _newlines _n)
  if(_n GREATER _max_lines)
    message("${_file}: ${_n} lines (at most ${_max_lines})")
    math(EXPR _bad "${_bad} + 1")
  endif()
  if(_text MATCHES "DESIGN\\.md")
    message("${_file}: cites DESIGN.md, which is not in the repository (cite docs/ or docs/references.md)")
    math(EXPR _bad "${_bad} + 1")
  endif()
endforeach()

if(_bad GREATER 0)
  message(FATAL_ERROR "${_bad} breach(es) of the rules in docs/architecture.md")
endif()
