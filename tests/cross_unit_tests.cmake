# Shared by the cross-built unit-test projects (tests/target/ for Cortex-M3 under QEMU, tests/avr/ for an AVR
# under simavr): the core, the Unity harness and the test support built for the target, one <test>.elf per
# tests/unit/test_*.c, and <build>/tests.txt (a first line FIRST_LINE, then one test name a line).
#   co_cross_unit_tests(RUNTIME <library: output, startup, exit> UNITY_CONFIG_DIR <dir of unity_config.h>
#                       FIRST_LINE <text> [CORE_DEFS <definitions of the core's configuration>...]
#                       [FIXTURE_DEFS <sizes of the test fixtures>...])
# Expects CO_ROOT (the repository) and CO_WARNINGS.
function(co_cross_unit_tests)
  cmake_parse_arguments(arg "" "RUNTIME;UNITY_CONFIG_DIR;FIRST_LINE" "CORE_DEFS;FIXTURE_DEFS" ${ARGN})
  file(GLOB co_core_sources ${CO_ROOT}/src/co_*.c)
  add_library(co_core STATIC ${co_core_sources})
  target_include_directories(co_core PUBLIC ${CO_ROOT}/include PRIVATE ${CO_ROOT}/src)
  target_compile_definitions(co_core PUBLIC ${arg_CORE_DEFS})
  target_compile_options(co_core PRIVATE ${CO_WARNINGS})

  add_library(unity STATIC ${CO_ROOT}/tests/unity/unity.c)
  target_include_directories(unity PUBLIC ${CO_ROOT}/tests/unity ${arg_UNITY_CONFIG_DIR})
  target_compile_definitions(unity PUBLIC UNITY_INCLUDE_CONFIG_H)
  target_link_libraries(unity PUBLIC ${arg_RUNTIME})

  add_library(co_test_support STATIC ${CO_ROOT}/tests/support/fake_port.c ${CO_ROOT}/tests/support/test_od.c
              ${CO_ROOT}/tests/support/fixture.c)
  target_include_directories(co_test_support PUBLIC ${CO_ROOT}/tests/support ${CO_ROOT}/src)
  target_compile_definitions(co_test_support PUBLIC ${arg_FIXTURE_DEFS})
  target_link_libraries(co_test_support PUBLIC co_core unity)
  target_compile_options(co_test_support PRIVATE ${CO_WARNINGS})

  # test_pdo_no_timers and test_emcy_fitted check the core compiled with a service part off, as on the host
  # (tests/CMakeLists.txt): each its own copy of the core and of the support it uses.
  set(co_variant_tests test_pdo_no_timers test_emcy_fitted)
  set(co_variant_test_pdo_no_timers CO_CONFIG_PDO_TIMERS=0)
  set(co_variant_test_emcy_fitted CO_CONFIG_EMCY_HISTORY=0 CO_CONFIG_EMCY_INHIBIT=0)
  foreach(v IN LISTS co_variant_tests)
    add_library(co_core_${v} STATIC ${co_core_sources})
    target_include_directories(co_core_${v} PUBLIC ${CO_ROOT}/include PRIVATE ${CO_ROOT}/src)
    target_compile_definitions(co_core_${v} PUBLIC ${arg_CORE_DEFS} ${co_variant_${v}})
    target_compile_options(co_core_${v} PRIVATE ${CO_WARNINGS})
    add_library(co_test_support_${v} STATIC ${CO_ROOT}/tests/support/fake_port.c ${CO_ROOT}/tests/support/test_od.c)
    target_include_directories(co_test_support_${v} PUBLIC ${CO_ROOT}/tests/support ${CO_ROOT}/src)
    target_compile_definitions(co_test_support_${v} PUBLIC ${arg_FIXTURE_DEFS})
    target_link_libraries(co_test_support_${v} PUBLIC co_core_${v} unity)
    target_compile_options(co_test_support_${v} PRIVATE ${CO_WARNINGS})
  endforeach()

  # Same list as the host build: every tests/unit/test_*.c but the host-only ones (tests/unit/host_only_tests.cmake).
  include(${CO_ROOT}/tests/unit/host_only_tests.cmake)
  file(GLOB co_unit_test_sources CONFIGURE_DEPENDS ${CO_ROOT}/tests/unit/test_*.c)
  foreach(t IN LISTS CO_HOST_ONLY_UNIT_TESTS)
    list(REMOVE_ITEM co_unit_test_sources ${CO_ROOT}/tests/unit/${t}.c)
  endforeach()
  file(WRITE ${CMAKE_BINARY_DIR}/tests.txt "${arg_FIRST_LINE}\n")
  foreach(src IN LISTS co_unit_test_sources)
    get_filename_component(t ${src} NAME_WE)
    add_executable(${t} ${src})
    set_target_properties(${t} PROPERTIES SUFFIX .elf)
    if(t IN_LIST co_variant_tests)
      target_link_libraries(${t} PRIVATE co_test_support_${t})
    else()
      target_link_libraries(${t} PRIVATE co_test_support)
    endif()
    target_compile_options(${t} PRIVATE ${CO_WARNINGS})
    file(APPEND ${CMAKE_BINARY_DIR}/tests.txt "${t}\n")
  endforeach()
endfunction()
