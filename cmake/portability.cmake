# Portability (docs/porting.md): the bare-metal reference port, its host tests, the footprint check and the
# target tests. Included at the end of the top-level CMakeLists.txt (configuration profiles: profile.cmake).

if(CMAKE_CROSSCOMPILING AND CO_BUILD_TESTS)
  message(FATAL_ERROR "A cross build has no host tests: configure it with -DCO_BUILD_TESTS=OFF (the toolchain "
                      "files of cmake/toolchains/ default to it); the unit tests run on a target with tools/target-tests")
endif()

# ---- The bare-metal reference port (ports/baremetal): portable, built in every configuration -----------
set(CO_PORT_BM ${PROJECT_SOURCE_DIR}/ports/baremetal)
add_library(co_port_baremetal STATIC ${CO_PORT_BM}/co_bm_ring.c ${CO_PORT_BM}/co_bm_clock.c ${CO_PORT_BM}/co_bm_nvm.c
            ${CO_PORT_BM}/co_bm_port.c)
target_include_directories(co_port_baremetal PUBLIC ${CO_PORT_BM})
target_link_libraries(co_port_baremetal PUBLIC co_core)
target_compile_options(co_port_baremetal PRIVATE ${CO_WARNINGS})
if(CMAKE_CROSSCOMPILING)
  # The example main loop: compiled (not linked: the board functions are the board's) as a check.
  add_library(co_port_baremetal_example OBJECT ${CO_PORT_BM}/example/main.c)
  target_link_libraries(co_port_baremetal_example PRIVATE co_port_baremetal od_sds)
  target_compile_options(co_port_baremetal_example PRIVATE ${CO_WARNINGS})
endif()

# ---- Footprint probes (tools/size-report): sizes on the target, and a -nostdlib link per device -------
add_library(co_footprint_probe OBJECT ${PROJECT_SOURCE_DIR}/cmake/footprint_probe.c)
target_link_libraries(co_footprint_probe PRIVATE od_pro_ionizer od_sds od_buerkert_fc co_core)
target_compile_options(co_footprint_probe PRIVATE ${CO_WARNINGS})
if(CMAKE_CROSSCOMPILING)
  foreach(dev pro_ionizer sds buerkert_fc)
    add_executable(co_freestanding_${dev} ${PROJECT_SOURCE_DIR}/cmake/freestanding_check.c)
    set_target_properties(co_freestanding_${dev} PROPERTIES SUFFIX .elf)
    target_compile_definitions(co_freestanding_${dev} PRIVATE CO_CHECK_OD=${dev}_od)
    target_compile_options(co_freestanding_${dev} PRIVATE ${CO_WARNINGS} -ffreestanding)
    target_link_libraries(co_freestanding_${dev} PRIVATE od_${dev} co_core gcc)
    target_link_options(co_freestanding_${dev} PRIVATE -nostdlib -nostartfiles
                        -T${PROJECT_SOURCE_DIR}/cmake/freestanding.ld -Wl,--gc-sections)
  endforeach()
endif()

if(CO_BUILD_TESTS AND NOT CMAKE_CROSSCOMPILING)
  find_package(Threads REQUIRED)
  set(co_port_test_launcher "")
  if(CO_VALGRIND)
    set(co_port_test_launcher ${VALGRIND} --quiet --error-exitcode=99 --leak-check=full --errors-for-leak-kinds=all)
  endif()
  foreach(t test_bm_ring test_bm_clock test_bm_nvm)
    add_executable(${t} ${CO_PORT_BM}/tests/${t}.c)
    target_link_libraries(${t} PRIVATE co_port_baremetal co_test_support unity Threads::Threads)
    target_compile_options(${t} PRIVATE ${CO_WARNINGS})
    add_test(NAME port/${t} COMMAND ${co_port_test_launcher} $<TARGET_FILE:${t}>)
    set_tests_properties(port/${t} PROPERTIES LABELS unit)
  endforeach()
endif()

# ---- Footprint: tools/size-report regenerates docs/footprint.md's table and compares ------------------
option(CO_FOOTPRINT_TEST "Register the footprint check (label footprint; needs the cross compilers)" OFF)
if(CO_FOOTPRINT_TEST AND CO_BUILD_TESTS)
  add_test(NAME footprint/docs
           COMMAND ${PROJECT_SOURCE_DIR}/tools/size-report --check --build-dir ${PROJECT_BINARY_DIR}/footprint)
  set_tests_properties(footprint/docs PROPERTIES LABELS footprint TIMEOUT 1800)
endif()

# One ctest test per unit test, <label>/test_*, that runs <dir>/test_*.elf with RUNNER --run ELF [ARGS...] and,
# where the host build has the same test, --host <its binary> (the per-case results must be the host's).
function(co_add_cross_unit_tests label dir runner)
  file(GLOB co_unit_test_sources ${PROJECT_SOURCE_DIR}/tests/unit/test_*.c)
  foreach(src IN LISTS co_unit_test_sources)
    get_filename_component(t ${src} NAME_WE)
    set(co_host_arg "")
    if(TARGET ${t})
      set(co_host_arg --host $<TARGET_FILE:${t}>)
    endif()
    add_test(NAME ${label}/${t} COMMAND ${runner} --run ${dir}/${t}.elf ${ARGN} ${co_host_arg})
    set_tests_properties(${label}/${t} PROPERTIES LABELS ${label} TIMEOUT 600)
  endforeach()
endfunction()

# ---- Target tests: tests/unit on a Cortex-M3 under QEMU (label target) ---------------------------------
option(CO_TARGET_TESTS "Build the unit tests for Cortex-M3 and run them under qemu-system-arm (label target)" OFF)
set(CO_TARGET_BOARD mps2-an385 CACHE STRING "QEMU board of the target tests: mps2-an385 or lm3s6965evb")
if(CO_TARGET_TESTS AND CO_BUILD_TESTS)
  include(ExternalProject)
  set(co_target_dir ${PROJECT_BINARY_DIR}/target-tests-${CO_TARGET_BOARD})
  ExternalProject_Add(co_target_tests
    SOURCE_DIR ${PROJECT_SOURCE_DIR}/tests/target
    BINARY_DIR ${co_target_dir}
    CMAKE_ARGS -DCMAKE_TOOLCHAIN_FILE=${PROJECT_SOURCE_DIR}/cmake/toolchains/arm-cortex-m3.cmake
               -DCO_TARGET_BOARD=${CO_TARGET_BOARD} -DCMAKE_BUILD_TYPE=MinSizeRel
    BUILD_ALWAYS ON
    INSTALL_COMMAND "")
  co_add_cross_unit_tests(target ${co_target_dir} ${PROJECT_SOURCE_DIR}/tools/target-tests --board ${CO_TARGET_BOARD})
endif()

# ---- AVR tests: tests/unit on an 8-bit ATmega1284P under simavr (label avr) ------------------------------
option(CO_AVR_TESTS "Build the unit tests for an 8-bit AVR and run them under simavr (label avr)" OFF)
if(CO_AVR_TESTS AND CO_BUILD_TESTS)
  include(ExternalProject)
  set(co_avr_dir ${PROJECT_BINARY_DIR}/avr-tests)
  ExternalProject_Add(co_avr_tests
    SOURCE_DIR ${PROJECT_SOURCE_DIR}/tests/avr
    BINARY_DIR ${co_avr_dir}
    CMAKE_ARGS -DCMAKE_TOOLCHAIN_FILE=${PROJECT_SOURCE_DIR}/cmake/toolchains/avr-atmega1284p.cmake
               -DCMAKE_BUILD_TYPE=MinSizeRel
    BUILD_ALWAYS ON
    INSTALL_COMMAND "")
  co_add_cross_unit_tests(avr ${co_avr_dir} ${PROJECT_SOURCE_DIR}/tools/avr-tests)
endif()
