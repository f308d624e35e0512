# The EDS/DCF reader: library co_eds and the host program canopen-eds (eds/, docs/eds.md).
# Sets CO_EDS_TOOL (the canopen-eds the build runs) and CO_EDS_TOOL_TARGET (what generation depends on).
set(CO_EDS_SOURCES eds/eds.c eds/eds_ini.c eds/eds_diag.c eds/eds_value.c eds/eds_info.c eds/eds_entries.c
                   eds/eds_objects.c eds/eds_dcf.c eds/eds_pdo.c eds/eds_write.c)
if(NOT CMAKE_CROSSCOMPILING)
  add_library(co_eds STATIC ${CO_EDS_SOURCES})
  target_include_directories(co_eds PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/eds>)
  target_compile_options(co_eds PRIVATE ${CO_WARNINGS})
  target_link_libraries(co_eds PRIVATE m)
  add_executable(canopen-eds eds/canopen_eds.c)
  target_link_libraries(canopen-eds PRIVATE co_eds)
  target_compile_options(canopen-eds PRIVATE ${CO_WARNINGS})
  set(CO_EDS_TOOL $<TARGET_FILE:canopen-eds>)
  set(CO_EDS_TOOL_TARGET canopen-eds)
else()
  # Cross build: the generator runs on the build machine, so the reader is built there with its C compiler, unless
  # one is given (tools/size-report builds it once for its 64 cross builds).
  set(CO_HOST_EDS_TOOL "" CACHE FILEPATH "A canopen-eds built for the build machine (cross builds only; empty: build one)")
endif()
if(CMAKE_CROSSCOMPILING AND CO_HOST_EDS_TOOL)
  set(CO_EDS_TOOL ${CO_HOST_EDS_TOOL})
  set(CO_EDS_TOOL_TARGET "")
elseif(CMAKE_CROSSCOMPILING)
  include(ExternalProject)
  set(CO_HOST_C_COMPILER cc CACHE STRING "The build machine's C compiler (for canopen-eds in cross builds)")
  set(host_dir ${PROJECT_BINARY_DIR}/host-eds)
  ExternalProject_Add(co_eds_host
    SOURCE_DIR ${PROJECT_SOURCE_DIR}/eds
    BINARY_DIR ${host_dir}
    CMAKE_ARGS -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_COMPILER=${CO_HOST_C_COMPILER}
    BUILD_BYPRODUCTS ${host_dir}/canopen-eds
    INSTALL_COMMAND "")
  set(CO_EDS_TOOL ${host_dir}/canopen-eds)
  set(CO_EDS_TOOL_TARGET co_eds_host)
endif()
