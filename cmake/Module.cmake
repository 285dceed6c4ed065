# patchscan_module(TARGET t OUTPUT name LOADER target DEFINE PREFIX SOURCES...): a module
# (core/module.h) built from SOURCES into the build tree's lib/ as OUTPUT.so, installed in
# lib/patchscan/, exporting only what its sources mark visible; the LOADER target is built
# after it and compiled with where to find it: PREFIX_NAME, PREFIX_BUILT, PREFIX_INSTALLED and
# PREFIX_FROM_BINDIR (the installed directory relative to the program's).
function(patchscan_module)
  cmake_parse_arguments(M "" "TARGET;OUTPUT;LOADER;DEFINE" "SOURCES" ${ARGN})
  set(_built ${PROJECT_BINARY_DIR}/lib)
  set(_installed ${CMAKE_INSTALL_FULL_LIBDIR}/patchscan)
  file(RELATIVE_PATH _from_bindir ${CMAKE_INSTALL_FULL_BINDIR} ${_installed})
  add_library(${M_TARGET} MODULE ${M_SOURCES})
  set_target_properties(${M_TARGET} PROPERTIES PREFIX "" OUTPUT_NAME ${M_OUTPUT}
                        LIBRARY_OUTPUT_DIRECTORY ${_built} CXX_VISIBILITY_PRESET hidden)
  target_include_directories(${M_TARGET} PRIVATE ${PROJECT_SOURCE_DIR}/src)
  # Static libraries linked in keep their symbols inside the module.
  target_link_options(${M_TARGET} PRIVATE -Wl,--exclude-libs,ALL)
  target_compile_definitions(${M_LOADER} PRIVATE
    ${M_DEFINE}_NAME="${M_OUTPUT}.so" ${M_DEFINE}_BUILT="${_built}"
    ${M_DEFINE}_INSTALLED="${_installed}" ${M_DEFINE}_FROM_BINDIR="${_from_bindir}")
  add_dependencies(${M_LOADER} ${M_TARGET})
  install(TARGETS ${M_TARGET} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}/patchscan)
endfunction()
