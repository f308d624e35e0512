# Cortex-M4F (ARMv7E-M, single-precision FPU, hard-float ABI): Debian's gcc-arm-none-eabi + picolibc.
#   cmake -S . -B build-cm4f --toolchain cmake/toolchains/arm-cortex-m4f.cmake -DCMAKE_BUILD_TYPE=MinSizeRel
set(CO_CROSS_PREFIX arm-none-eabi-)
set(CO_CROSS_PROCESSOR cortex-m4)
set(CO_CROSS_ARCH_FLAGS "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
include(${CMAKE_CURRENT_LIST_DIR}/gcc-bare-metal.cmake)
