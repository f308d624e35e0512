# 32-bit big-endian PowerPC, Linux user space: the byte-order check of the core, its unit tests and the device
# models' tests, which ctest runs under qemu-ppc (tests/CMakeLists.txt: the crosscompiling emulator launches them).
# Static: qemu-ppc runs the binaries without a PowerPC C library at run time. Debian 12 packages:
# gcc-powerpc-linux-gnu, qemu-user. docs/porting.md "Unit tests on a big-endian CPU":
#   cmake -S . -B build-big-endian --toolchain cmake/toolchains/powerpc-linux-gnu.cmake -DCO_BUILD_EMULATOR=OFF \
#         -DCO_PORTABILITY=OFF -DCO_BENCH=OFF -DCO_INSTALL=OFF
#   cmake --build build-big-endian && ctest --test-dir build-big-endian -L unit
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR powerpc)
set(CMAKE_C_COMPILER powerpc-linux-gnu-gcc)
set(CMAKE_EXE_LINKER_FLAGS_INIT "-static")
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-ppc)
set(CMAKE_FIND_ROOT_PATH /usr/powerpc-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
