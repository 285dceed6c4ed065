# cmake -DGENERATED=<file> -DCHECKED_IN=<file> -P CheckGenerated.cmake
#
# Fails when a page generated at build time (the command-line reference) differs from the
# copy kept in the repository, and says how to bring the copy up to date.
cmake_minimum_required(VERSION 3.25)
if(NOT EXISTS "${GENERATED}")
  message(FATAL_ERROR "${GENERATED} was not generated: build first")
endif()
file(READ "${GENERATED}" _generated)
file(READ "${CHECKED_IN}" _checked_in)
if(NOT _generated STREQUAL _checked_in)
  message(FATAL_ERROR "${CHECKED_IN} is out of date with the program's options: cp ${GENERATED} ${CHECKED_IN}")
endif()
