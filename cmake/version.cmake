# The project's version in the core's header and in the canopen-emu program.
#
# include/co/co_version.h is a plain header (the core builds without CMake too); configuring fails when it and
# project(VERSION) disagree, so a release cannot carry two versions.
file(STRINGS ${PROJECT_SOURCE_DIR}/include/co/co_version.h co_version_lines REGEX "^#define CO_VERSION_(MAJOR|MINOR|PATCH) ")
set(co_header_version "")
foreach(part MAJOR MINOR PATCH)
  string(REGEX MATCH "CO_VERSION_${part} ([0-9]+)" _ "${co_version_lines}")
  list(APPEND co_header_version "${CMAKE_MATCH_1}")
endforeach()
list(JOIN co_header_version "." co_header_version)
file(STRINGS ${PROJECT_SOURCE_DIR}/include/co/co_version.h co_version_string REGEX "^#define CO_VERSION_STRING ")
if(NOT co_version_string MATCHES "\"${co_header_version}\"")
  message(FATAL_ERROR "include/co/co_version.h: CO_VERSION_STRING is not \"${co_header_version}\"")
endif()
if(NOT co_header_version STREQUAL PROJECT_VERSION)
  message(FATAL_ERROR "include/co/co_version.h says ${co_header_version}, project(VERSION) says ${PROJECT_VERSION}: "
                      "change both")
endif()

if(NOT CO_BUILD_EMULATOR)
  return()  # only the program prints its revision
endif()

# co_emu_version: an interface library giving emu_version.h (EMU_VERSION, EMU_GIT_REVISION). The revision is
# `git describe` of this source tree, taken at every build (not only at configure time, which would go stale
# after the next commit) and written only when it changed, so an unchanged tree rebuilds nothing. Outside a
# git checkout of this project (a release tarball, a copy, a parent project's repository) it is empty.
find_package(Git QUIET)
set(co_version_dir ${PROJECT_BINARY_DIR}/generated)
add_custom_target(co_emu_version_header
  COMMAND ${CMAKE_COMMAND} -DSOURCE_DIR=${PROJECT_SOURCE_DIR} -DGIT=${GIT_EXECUTABLE}
          -DVERSION=${PROJECT_VERSION} -DOUT=${co_version_dir}/emu_version.h
          -P ${PROJECT_SOURCE_DIR}/cmake/write_version_header.cmake
  BYPRODUCTS ${co_version_dir}/emu_version.h
  COMMENT "Version header (git describe)"
  VERBATIM)
add_library(co_emu_version INTERFACE)
target_include_directories(co_emu_version INTERFACE $<BUILD_INTERFACE:${co_version_dir}>)
add_dependencies(co_emu_version co_emu_version_header)
