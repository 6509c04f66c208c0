# Runs at install time (cmake --install [--prefix P], cpack), so that what the units name
# is where the install put it: the binaries in <prefix>/bin, the configuration and plans
# in /etc/floorpose for prefix /usr (else <prefix>/etc/floorpose), the units in
# /lib/systemd/system for /usr (Debian bookworm's place; else <prefix>/lib/systemd/system,
# which systemd also reads for /usr/local). FLOORPOSE_SOURCE_DIR is set by the caller.
set(_prefix "${CMAKE_INSTALL_PREFIX}")
if(_prefix STREQUAL "/usr")
  set(_etc "/etc/floorpose")
  set(_unit_dir "/lib/systemd/system")
else()
  set(_etc "${_prefix}/etc/floorpose")
  set(_unit_dir "${_prefix}/lib/systemd/system")
endif()
set(_staged "${CMAKE_CURRENT_BINARY_DIR}/installed-units")
foreach(_unit floorposed.service floorpose-dashboard.service)
  file(READ "${FLOORPOSE_SOURCE_DIR}/systemd/${_unit}" _text)
  string(REPLACE "/usr/local/bin/" "${_prefix}/bin/" _text "${_text}")
  string(REPLACE "/etc/floorpose/" "${_etc}/" _text "${_text}")
  file(WRITE "${_staged}/${_unit}" "${_text}")
endforeach()
file(INSTALL DESTINATION "${_unit_dir}" TYPE FILE PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ
     FILES "${_staged}/floorposed.service" "${_staged}/floorpose-dashboard.service")
file(INSTALL DESTINATION "${_etc}" TYPE FILE PERMISSIONS OWNER_READ OWNER_WRITE GROUP_READ WORLD_READ
     FILES "${FLOORPOSE_SOURCE_DIR}/systemd/floorposed.conf")
file(INSTALL DESTINATION "${_etc}" TYPE DIRECTORY
     DIR_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE
     FILES "${FLOORPOSE_SOURCE_DIR}/tools/package/plans")
