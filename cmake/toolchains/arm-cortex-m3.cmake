# Cortex-M3 (ARMv7-M, no FPU): the CPU of the QEMU boards used by the target tests (mps2-an385,
# lm3s6965evb). Debian's gcc-arm-none-eabi + picolibc.
#   cmake -S . -B build-cm3 --toolchain cmake/toolchains/arm-cortex-m3.cmake -DCMAKE_BUILD_TYPE=MinSizeRel
set(CO_CROSS_PREFIX arm-none-eabi-)
set(CO_CROSS_PROCESSOR cortex-m3)
set(CO_CROSS_ARCH_FLAGS "-mcpu=cortex-m3 -mthumb -mfloat-abi=soft")
include(${CMAKE_CURRENT_LIST_DIR}/gcc-bare-metal.cmake)
