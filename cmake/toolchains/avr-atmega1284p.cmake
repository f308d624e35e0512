# 8-bit AVR (ATmega1284P: 128 KiB flash, 16 KiB SRAM; 16-bit int, 32-bit double in avr-gcc), for the
# portability check of the core and its unit tests under simavr (tests/avr/, tools/avr-tests).
# Debian 12 packages: gcc-avr, avr-libc, simavr.
#   cmake -S tests/avr -B build-avr --toolchain cmake/toolchains/avr-atmega1284p.cmake
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR avr)
set(CMAKE_C_COMPILER avr-gcc)
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)
set(CO_AVR_MCU atmega1284p)
set(CMAKE_C_FLAGS_INIT "-mmcu=${CO_AVR_MCU} -ffunction-sections -fdata-sections")
set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,--gc-sections")
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
