# Configuration profile of the core (docs/porting.md): a header of cmake/profiles/ (or any path) that replaces
# the defaults of include/co/co_config.h, given to every user of the core as CO_CONFIG_HEADER. Included by the
# top-level CMakeLists.txt right after the co_core target.
set(CO_PROFILE "" CACHE STRING
    "Core configuration profile: eltex, full (cmake/profiles/<name>.h) or a header path; empty = co_config.h defaults")
if(CO_PROFILE)
  if(EXISTS ${PROJECT_SOURCE_DIR}/cmake/profiles/${CO_PROFILE}.h)
    set(co_profile_header ${PROJECT_SOURCE_DIR}/cmake/profiles/${CO_PROFILE}.h)
  elseif(IS_ABSOLUTE "${CO_PROFILE}" AND EXISTS "${CO_PROFILE}")
    set(co_profile_header ${CO_PROFILE})
  else()
    message(FATAL_ERROR "CO_PROFILE=${CO_PROFILE}: no cmake/profiles/${CO_PROFILE}.h and not an existing header path")
  endif()
  # PUBLIC: everything that sees co_node_t (od_*, devices, tests) must agree on its layout. Installed, the
  # profile goes with the headers as co/co_profile.h (cmake/install.cmake), so the installed package carries the
  # configuration its libraries were built with.
  target_compile_definitions(co_core PUBLIC "$<BUILD_INTERFACE:CO_CONFIG_HEADER=\"${co_profile_header}\">"
                                            "$<INSTALL_INTERFACE:CO_CONFIG_HEADER=\"co/co_profile.h\">")
  message(STATUS "core configuration profile: ${co_profile_header}")
endif()
