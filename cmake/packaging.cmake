# Packages from the same build as `cmake --install` (docs/installing.md): `cpack -G DEB` in the build directory
# gives canopen-emu_<version>_<arch>.deb (prefix /usr), `cpack -G TGZ` a relocatable tarball. One package holds
# everything: the program, its man page and EDS files, and the headers, static libraries, CMake package and
# pkg-config files for building against the core. Included by cmake/install.cmake.
set(CPACK_PACKAGE_NAME canopen-emu)
set(CPACK_PACKAGE_VENDOR "canopen-emu")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
# Debian's long description: CPack indents each line; lines are kept under 80 columns.
string(JOIN "\n" CPACK_PACKAGE_DESCRIPTION
  "canopen-emu runs emulated CANopen devices (Eltex PRO IONIZER, Eltex SDS, a"
  "Buerkert flow controller) on a SocketCAN interface, for testing PLCs and"
  "CANopen masters. The package also holds the C99 CANopen slave core (CiA"
  "301/305; no malloc, no writable globals), the generated object dictionaries"
  "and the device models as static libraries with headers, a CMake package"
  "(find_package(canopen-emu)) and pkg-config files (canopen-core).")
set(CPACK_PACKAGE_CONTACT "canopen-emu developers <canopen-emu@users.noreply.invalid>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_STRIP_FILES ON)
set(CPACK_GENERATOR TGZ)
set(CPACK_SOURCE_GENERATOR TGZ)
set(CPACK_SOURCE_IGNORE_FILES "/\\\\.git/" "/build[^/]*/" "/__pycache__/")

set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION electronics)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)  # Depends: from the program's shared libraries (dpkg-shlibdeps: libc6)
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "can-utils")
include(CPack)
