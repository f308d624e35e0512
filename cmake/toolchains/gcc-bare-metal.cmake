# Shared part of the bare-metal toolchain files (included by arm-cortex-*.cmake and riscv32-imac.cmake;
# not a toolchain file on its own). Expects CO_CROSS_PREFIX (e.g. arm-none-eabi-), CO_CROSS_ARCH_FLAGS
# and CO_CROSS_PROCESSOR. Debian 12 packages: gcc-arm-none-eabi + picolibc-arm-none-eabi (or
# libnewlib-arm-none-eabi), gcc-riscv64-unknown-elf + picolibc-riscv64-unknown-elf.
#
# A cross build contains only the portable parts: the core (co_core), the generated object dictionaries
# (od_*), the device models (co_devices) and the bare-metal port template (co_port_baremetal). The
# host-only parts are left out by themselves: the Linux program needs CMAKE_SYSTEM_NAME Linux, and the
# host test suite defaults to OFF here (CO_BUILD_TESTS; the unit tests run on a target with
# tools/target-tests). Use -DCMAKE_BUILD_TYPE=MinSizeRel for -Os.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR ${CO_CROSS_PROCESSOR})
set(CMAKE_C_COMPILER ${CO_CROSS_PREFIX}gcc)
set(CMAKE_ASM_COMPILER ${CO_CROSS_PREFIX}gcc)
# No OS to link a test program against: CMake's compiler checks build a static library instead.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

# The C library: picolibc (default; both Debian packages ship it for every multilib used here) or newlib
# (arm only: libnewlib-arm-none-eabi, nano variant). Only its headers matter to the core (<string.h>);
# the core links against memcpy/memset/memcmp/memmove and nothing else (checked by tools/size-report).
if(NOT DEFINED CO_LIBC)
  set(CO_LIBC picolibc)
endif()
set(CO_LIBC ${CO_LIBC} CACHE STRING "C library of the cross build: picolibc or newlib")
list(APPEND CMAKE_TRY_COMPILE_PLATFORM_VARIABLES CO_LIBC CO_CROSS_PREFIX CO_CROSS_ARCH_FLAGS CO_CROSS_PROCESSOR)
if(CO_LIBC STREQUAL "picolibc")
  set(co_libc_flags "--specs=picolibc.specs")
elseif(CO_LIBC STREQUAL "newlib")
  set(co_libc_flags "--specs=nano.specs")
else()
  message(FATAL_ERROR "CO_LIBC must be picolibc or newlib, not '${CO_LIBC}'")
endif()

set(CMAKE_C_FLAGS_INIT "${CO_CROSS_ARCH_FLAGS} ${co_libc_flags} -ffunction-sections -fdata-sections")
set(CMAKE_ASM_FLAGS_INIT "${CO_CROSS_ARCH_FLAGS}")
# (CMAKE_C_FLAGS, with the architecture and the specs file, are on the link line too.)
set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,--gc-sections")

# Host programs (Python for tools/odgen.py) come from the host; libraries and headers from the target.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# Portable parts only unless asked otherwise (option() keeps an existing cache value).
if(NOT DEFINED CO_BUILD_TESTS)
  set(CO_BUILD_TESTS OFF CACHE BOOL "Build the unit tests")
endif()
