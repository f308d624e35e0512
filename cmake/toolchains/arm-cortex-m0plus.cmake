# Cortex-M0+ (ARMv6-M, Thumb-1, no FPU, no hardware divide): Debian's gcc-arm-none-eabi + picolibc.
#   cmake -S . -B build-cm0plus --toolchain cmake/toolchains/arm-cortex-m0plus.cmake -DCMAKE_BUILD_TYPE=MinSizeRel
set(CO_CROSS_PREFIX arm-none-eabi-)
set(CO_CROSS_PROCESSOR cortex-m0plus)
set(CO_CROSS_ARCH_FLAGS "-mcpu=cortex-m0plus -mthumb -mfloat-abi=soft")
include(${CMAKE_CURRENT_LIST_DIR}/gcc-bare-metal.cmake)
