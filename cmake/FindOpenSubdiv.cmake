# Find OpenSubdiv's CPU library and headers.
# Debian's OpenSubdivConfig.cmake names a static libosdCPU.a that the package does not
# ship, so this module looks for the shared library and the headers directly.
# Defines OpenSubdiv_FOUND, OpenSubdiv_VERSION and the imported target OpenSubdiv::osdCPU.
find_path(OpenSubdiv_INCLUDE_DIR NAMES opensubdiv/version.h)
find_library(OpenSubdiv_LIBRARY NAMES osdCPU)

if(OpenSubdiv_INCLUDE_DIR AND EXISTS "${OpenSubdiv_INCLUDE_DIR}/opensubdiv/version.h")
  set(_osd_parts "")
  foreach(_part MAJOR MINOR PATCH)
    file(STRINGS "${OpenSubdiv_INCLUDE_DIR}/opensubdiv/version.h" _line
         REGEX "#define OPENSUBDIV_VERSION_${_part} +[0-9]+")
    string(REGEX REPLACE ".* ([0-9]+)$" "\\1" _num "${_line}")
    list(APPEND _osd_parts "${_num}")
  endforeach()
  list(JOIN _osd_parts "." OpenSubdiv_VERSION)
endif()

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenSubdiv
  REQUIRED_VARS OpenSubdiv_LIBRARY OpenSubdiv_INCLUDE_DIR
  VERSION_VAR OpenSubdiv_VERSION)

if(OpenSubdiv_FOUND AND NOT TARGET OpenSubdiv::osdCPU)
  add_library(OpenSubdiv::osdCPU UNKNOWN IMPORTED)
  set_target_properties(OpenSubdiv::osdCPU PROPERTIES
    IMPORTED_LOCATION "${OpenSubdiv_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${OpenSubdiv_INCLUDE_DIR}")
endif()
mark_as_advanced(OpenSubdiv_INCLUDE_DIR OpenSubdiv_LIBRARY)
