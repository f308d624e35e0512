# Installation (docs/installing.md): `cmake --install <build> --prefix DIR` gives
#   include/co/                 the core's public headers (co/co.h)
#   include/co_od/              the generated object dictionaries of the three devices (<device>_od.h)
#   include/co_devices/         the device-model API (device.h, <model>/<model>.h)
#   lib/                        libco_core.a, libod_<device>.a, libco_devices.a
#   lib/cmake/canopen-emu/      the CMake package: find_package(canopen-emu CONFIG), targets canopen-emu::core,
#                               ::od_pro_ionizer, ::od_sds, ::od_buerkert_fc, ::devices
#   lib/pkgconfig/              canopen-core.pc, canopen-od-<device>.pc, canopen-devices.pc
#   bin/canopen-emu, share/man/man1/canopen-emu.1.gz, share/canopen-emu/eds/<device>.eds, share/doc/canopen-emu/
# Everything is relative to the prefix (the CMake package and the .pc files find their prefix from where they
# lie), so an installed tree can be moved. Included by the top-level CMakeLists.txt when CO_INSTALL is on.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(co_package canopen-emu)
set(co_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/${co_package})
set(co_pkgconfig_dir ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
set(co_od_include_dir ${CMAKE_INSTALL_INCLUDEDIR}/co_od)
set(co_devices_include_dir ${CMAKE_INSTALL_INCLUDEDIR}/co_devices)

# ---- Libraries and headers ------------------------------------------------------------------------------
target_include_directories(co_core INTERFACE $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
install(DIRECTORY include/co DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.h")
if(co_profile_header)  # CO_PROFILE (cmake/profile.cmake): the installed package keeps the built configuration
  install(FILES ${co_profile_header} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/co RENAME co_profile.h)
  set(co_pc_profile_cflags " -DCO_CONFIG_HEADER=<co/co_profile.h>")
endif()
set(co_installed_libraries co_core)

# co_pkgconfig(<module> <library> <description> <requires> <extra cflags>): lib/pkgconfig/<module>.pc.
# The prefix is ${pcfiledir} relative, so `--prefix DIR` at install time and a moved tree both work.
file(RELATIVE_PATH co_pc_to_prefix /prefix/${co_pkgconfig_dir} /prefix)
string(REGEX REPLACE "/$" "" co_pc_to_prefix "${co_pc_to_prefix}")
function(co_pkgconfig module library description requires cflags)
  set(pc "prefix=\${pcfiledir}/${co_pc_to_prefix}
includedir=\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}
libdir=\${prefix}/${CMAKE_INSTALL_LIBDIR}

Name: ${module}
Description: ${description}
Version: ${PROJECT_VERSION}
Requires: ${requires}
Cflags: -I\${includedir}${cflags}
Libs: -L\${libdir} -l${library}
")
  file(GENERATE OUTPUT ${PROJECT_BINARY_DIR}/pkgconfig/${module}.pc CONTENT "${pc}")
  install(FILES ${PROJECT_BINARY_DIR}/pkgconfig/${module}.pc DESTINATION ${co_pkgconfig_dir})
endfunction()
co_pkgconfig(canopen-core co_core "CANopen slave core (CiA 301/305), C99, no malloc" "" "${co_pc_profile_cflags}")

if(CO_DEVICES)
  set(co_od_modules "")
  foreach(od IN LISTS CO_OD_DEVICES)  # "<device>:<c_name>", set by co_add_od()
    string(REPLACE ":" ";" od "${od}")
    list(GET od 0 device)
    list(GET od 1 c_name)
    target_include_directories(od_${c_name} INTERFACE $<INSTALL_INTERFACE:${co_od_include_dir}>)
    install(FILES ${CO_OD_OUT}/${c_name}_od.h DESTINATION ${co_od_include_dir})
    install(FILES od/${device}.eds DESTINATION ${CMAKE_INSTALL_DATADIR}/${co_package}/eds)
    list(APPEND co_installed_libraries od_${c_name})
    string(REPLACE "_" "-" module canopen-od-${c_name})
    co_pkgconfig(${module} od_${c_name} "CANopen object dictionary generated from ${device}.eds (canopen-emu)"
                 canopen-core " -I\${includedir}/co_od")
    list(APPEND co_od_modules ${module})
  endforeach()

  target_include_directories(co_devices INTERFACE $<INSTALL_INTERFACE:${co_devices_include_dir}>)
  install(FILES devices/device.h devices/device_words.h DESTINATION ${co_devices_include_dir})
  foreach(model pro_ionizer sds buerkert)
    install(FILES devices/${model}/${model}.h DESTINATION ${co_devices_include_dir}/${model})
  endforeach()
  list(APPEND co_installed_libraries co_devices)
  list(JOIN co_od_modules " " co_od_modules)
  co_pkgconfig(canopen-devices co_devices "Device models of canopen-emu (Eltex PRO IONIZER, Eltex SDS, Buerkert)"
               "${co_od_modules}" " -I\${includedir}/co_devices")
endif()

install(TARGETS ${co_installed_libraries} EXPORT canopen-emu-targets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})

# ---- The CMake package ------------------------------------------------------------------------------------
install(EXPORT canopen-emu-targets NAMESPACE canopen-emu:: DESTINATION ${co_cmake_dir} FILE canopen-emu-targets.cmake)
configure_package_config_file(cmake/canopen-emu-config.cmake.in ${PROJECT_BINARY_DIR}/canopen-emu-config.cmake
                              INSTALL_DESTINATION ${co_cmake_dir} PATH_VARS CMAKE_INSTALL_DATADIR)
# 0.x: a minor release may change the API, so only the same major.minor satisfies a request.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/canopen-emu-config-version.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/canopen-emu-config.cmake ${PROJECT_BINARY_DIR}/canopen-emu-config-version.cmake
        DESTINATION ${co_cmake_dir})

# ---- The program, its man page, the device descriptions, documents ------------------------------------------
if(TARGET canopen-emu)
  install(TARGETS canopen-emu RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  # Debian installs man pages compressed (gzip -9n: no name, no time stamp, so the package is reproducible).
  find_program(CO_GZIP gzip)
  set(co_man ${PROJECT_SOURCE_DIR}/docs/man/canopen-emu.1)
  if(CO_GZIP)
    add_custom_command(OUTPUT ${PROJECT_BINARY_DIR}/man/canopen-emu.1.gz
      COMMAND ${CMAKE_COMMAND} -E make_directory ${PROJECT_BINARY_DIR}/man
      COMMAND ${CMAKE_COMMAND} -DGZIP=${CO_GZIP} -DIN=${co_man} -DOUT=${PROJECT_BINARY_DIR}/man/canopen-emu.1.gz
              -P ${PROJECT_SOURCE_DIR}/cmake/gzip_file.cmake
      DEPENDS ${co_man} ${PROJECT_SOURCE_DIR}/cmake/gzip_file.cmake
      COMMENT "Compressing the man page" VERBATIM)
    add_custom_target(co_man_page ALL DEPENDS ${PROJECT_BINARY_DIR}/man/canopen-emu.1.gz)
    install(FILES ${PROJECT_BINARY_DIR}/man/canopen-emu.1.gz DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
  else()
    install(FILES ${co_man} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
  endif()
endif()
if(TARGET canopen-eds)
  install(TARGETS canopen-eds RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})  # the EDS/DCF checker (docs/eds.md)
endif()
install(FILES README.md CHANGELOG.md DESTINATION ${CMAKE_INSTALL_DATADIR}/doc/${co_package})

# ---- Packages: cpack -G DEB (and TGZ) from the same build ----------------------------------------------------
if(PROJECT_IS_TOP_LEVEL)
  include(cmake/packaging.cmake)
endif()
