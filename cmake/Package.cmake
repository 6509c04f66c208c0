# Installation and the Debian package (`cmake --build build --target package`, cpack -G DEB):
# the binaries, the systemd units naming the paths they are installed at, the
# configuration as a conffile, a plans folder, the floorpose system user (sysusers.d),
# man pages, and Debian's copyright and changelog. dpkg-shlibdeps names the runtime
# libraries the package depends on.
include(GNUInstallDirs)

install(CODE "set(FLOORPOSE_SOURCE_DIR \"${PROJECT_SOURCE_DIR}\")")
install(SCRIPT "${PROJECT_SOURCE_DIR}/cmake/InstallSystem.cmake")
install(FILES "${PROJECT_SOURCE_DIR}/tools/package/sysusers.conf"
        DESTINATION lib/sysusers.d RENAME floorpose.conf)

# Man pages and the changelog, compressed as Debian wants them (gzip -9n: no name, no
# time, the same bytes every build).
find_program(GZIP gzip REQUIRED)
configure_file("${PROJECT_SOURCE_DIR}/tools/package/changelog.in"
               "${PROJECT_BINARY_DIR}/tools/package/changelog" @ONLY)
set(_gz)
foreach(_pair "docs/man/floorposed.8|man8" "docs/man/floorpose.1|man1"
        "${PROJECT_BINARY_DIR}/tools/package/changelog|doc")
  string(REPLACE "|" ";" _pair "${_pair}")
  list(GET _pair 0 _src)
  list(GET _pair 1 _where)
  if(NOT IS_ABSOLUTE "${_src}")
    set(_src "${PROJECT_SOURCE_DIR}/${_src}")
  endif()
  get_filename_component(_name "${_src}" NAME)
  if(_where STREQUAL "doc")
    set(_name changelog)
  endif()
  set(_out "${PROJECT_BINARY_DIR}/tools/package/${_name}.gz")
  add_custom_command(OUTPUT "${_out}" COMMAND ${GZIP} -9nc "${_src}" > "${_out}"
                     DEPENDS "${_src}" VERBATIM)
  list(APPEND _gz "${_out}")
  if(_where STREQUAL "doc")
    install(FILES "${_out}" DESTINATION "${CMAKE_INSTALL_DOCDIR}")
  else()
    install(FILES "${_out}" DESTINATION "${CMAKE_INSTALL_MANDIR}/${_where}")
  endif()
endforeach()
add_custom_target(compressed-docs ALL DEPENDS ${_gz})
install(FILES "${PROJECT_SOURCE_DIR}/tools/package/copyright" DESTINATION "${CMAKE_INSTALL_DOCDIR}")

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME floorpose)
set(CPACK_PACKAGE_VERSION "${PROJECT_VERSION}")
set(CPACK_PACKAGE_CONTACT "floorpose developers <floorpose@floorpose.dev>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "indoor positioning of AR headsets on floor plans")
set(CPACK_PACKAGE_DESCRIPTION
    "floorposed receives a headset's SLAM poses and spatial mesh over Cyclone
DDS, aligns its walls to a floor plan as the SLAM drifts, and publishes every
pose on the plan with a reliability flag. The floorpose tool imports plans,
evaluates recordings and serves the team's dashboard.")
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# floorposed opens PROJ only for plans in longitude/latitude (platform/wgs84.cc), which
# dpkg-shlibdeps cannot see: its package by Debian's name for the soname (libproj25).
find_package(PROJ CONFIG REQUIRED)
get_target_property(_proj_configs PROJ::proj IMPORTED_CONFIGURATIONS)
list(GET _proj_configs 0 _proj_config)
get_target_property(_proj_soname PROJ::proj IMPORTED_SONAME_${_proj_config})
string(REGEX REPLACE "^(lib[^.]+)\\.so\\.([0-9]+)$" "\\1\\2" _proj_package "${_proj_soname}")
set(CPACK_DEBIAN_PACKAGE_DEPENDS "${_proj_package}")
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_STRIP_FILES ON)
file(WRITE "${PROJECT_BINARY_DIR}/tools/package/conffiles" "/etc/floorpose/floorposed.conf\n")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    "${PROJECT_BINARY_DIR}/tools/package/conffiles;${PROJECT_SOURCE_DIR}/tools/package/postinst")
set(CPACK_PACKAGING_INSTALL_PREFIX "/usr")
include(CPack)
