# Find Open CASCADE Technology's toolkits and headers.
# Debian's OpenCASCADEConfig.cmake cannot be used as it is: a find_package with components
# only fails on imported targets it does not define, its targets carry no include
# directories, it adds compile definitions to the caller's directory, and it lists the Draw
# toolkits (libocct-draw-dev). This module looks for each toolkit asked for directly.
#
#   find_package(OpenCASCADE 7.6 REQUIRED COMPONENTS TKernel TKMath TKBRep ...)
#
# Defines OpenCASCADE_FOUND, OpenCASCADE_VERSION, OpenCASCADE_INCLUDE_DIR and, for each
# component found, the imported target OpenCASCADE::<toolkit> with the include directory.
find_path(OpenCASCADE_INCLUDE_DIR NAMES Standard_Version.hxx PATH_SUFFIXES opencascade)

if(OpenCASCADE_INCLUDE_DIR AND EXISTS "${OpenCASCADE_INCLUDE_DIR}/Standard_Version.hxx")
  set(_occt_parts "")
  foreach(_part MAJOR MINOR MAINTENANCE)
    file(STRINGS "${OpenCASCADE_INCLUDE_DIR}/Standard_Version.hxx" _line
         REGEX "#define OCC_VERSION_${_part} +[0-9]+")
    string(REGEX REPLACE ".* ([0-9]+)$" "\\1" _num "${_line}")
    list(APPEND _occt_parts "${_num}")
  endforeach()
  list(JOIN _occt_parts "." OpenCASCADE_VERSION)
endif()

foreach(_toolkit IN LISTS OpenCASCADE_FIND_COMPONENTS)
  find_library(OpenCASCADE_${_toolkit}_LIBRARY NAMES ${_toolkit})
  mark_as_advanced(OpenCASCADE_${_toolkit}_LIBRARY)
  if(OpenCASCADE_${_toolkit}_LIBRARY)
    set(OpenCASCADE_${_toolkit}_FOUND TRUE)
  endif()
endforeach()

include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(OpenCASCADE
  REQUIRED_VARS OpenCASCADE_INCLUDE_DIR
  VERSION_VAR OpenCASCADE_VERSION
  HANDLE_COMPONENTS)

if(OpenCASCADE_FOUND)
  foreach(_toolkit IN LISTS OpenCASCADE_FIND_COMPONENTS)
    if(OpenCASCADE_${_toolkit}_FOUND AND NOT TARGET OpenCASCADE::${_toolkit})
      add_library(OpenCASCADE::${_toolkit} UNKNOWN IMPORTED)
      set_target_properties(OpenCASCADE::${_toolkit} PROPERTIES
        IMPORTED_LOCATION "${OpenCASCADE_${_toolkit}_LIBRARY}"
        INTERFACE_INCLUDE_DIRECTORIES "${OpenCASCADE_INCLUDE_DIR}")
    endif()
  endforeach()
endif()
mark_as_advanced(OpenCASCADE_INCLUDE_DIR)
