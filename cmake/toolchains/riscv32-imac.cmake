# RISC-V RV32IMAC, ILP32 (e.g. GD32VF103, ESP32-C3-class cores without F): Debian's
# gcc-riscv64-unknown-elf (multilib, rv32imac/ilp32 included) + picolibc-riscv64-unknown-elf.
#   cmake -S . -B build-rv32imac --toolchain cmake/toolchains/riscv32-imac.cmake -DCMAKE_BUILD_TYPE=MinSizeRel
set(CO_CROSS_PREFIX riscv64-unknown-elf-)
set(CO_CROSS_PROCESSOR riscv32)
set(CO_CROSS_ARCH_FLAGS "-march=rv32imac -mabi=ilp32 -mcmodel=medlow")
include(${CMAKE_CURRENT_LIST_DIR}/gcc-bare-metal.cmake)
