# The Debian packages, built with CPack's DEB generator (`cpack --config build/CPackConfig.cmake`,
# or `scripts/setup.sh package`): `selfsense` (the programs, the systemd unit, the system user,
# the devices' group, the configurations in /etc/selfsense, the simulated transducer under
# /usr/share/selfsense, the man pages) and `libselfsense-dev` (headers, static libraries, CMake package).
# The system files are installed with absolute paths and EXCLUDE_FROM_ALL: into the package,
# never by a plain `cmake --install`.
set(_pkg ${PROJECT_BINARY_DIR}/packaging)
set(_share /usr/share/selfsense)

# A version that grows: the project's version and the number of commits (0.1.0+git282).
set(SELFSENSE_PACKAGE_VERSION "" CACHE STRING "Debian version of the packages (default: project version + git commit count)")
set(_version "${SELFSENSE_PACKAGE_VERSION}")
set(_date "")
if(NOT _version)
  execute_process(COMMAND git -C ${PROJECT_SOURCE_DIR} rev-list --count HEAD
    OUTPUT_VARIABLE _commits OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE _git_rc ERROR_QUIET)
  if(_git_rc EQUAL 0 AND _commits MATCHES "^[0-9]+$")
    set(_version "${PROJECT_VERSION}+git${_commits}")
  else()
    set(_version "${PROJECT_VERSION}")
  endif()
endif()
execute_process(COMMAND git -C ${PROJECT_SOURCE_DIR} log -1 --format=%aD
  OUTPUT_VARIABLE _date OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
execute_process(COMMAND git -C ${PROJECT_SOURCE_DIR} rev-parse --short=12 HEAD
  OUTPUT_VARIABLE _hash OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT _date)
  string(TIMESTAMP _date "%a, %d %b %Y %H:%M:%S +0000" UTC)
endif()
set(SELFSENSE_PACKAGE_MAINTAINER "selfsense maintainers <selfsense@example.org>" CACHE STRING
  "Maintainer of the Debian packages (a real address for a release)")
set(_maintainer "${SELFSENSE_PACKAGE_MAINTAINER}")

# The configurations, as installed: the model and the simulated bench from /usr/share/selfsense,
# recordings, telemetry and the control socket where the unit's directories are.
function(selfsense_package_config source destination)
  # Written at configure time: a changed file must configure again, or the package keeps the old.
  set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
    ${PROJECT_SOURCE_DIR}/config/${source})
  file(READ ${PROJECT_SOURCE_DIR}/config/${source} _text)
  set(_before "${_text}")
  string(REGEX REPLACE "model: models/" "model: ${_share}/models/" _text "${_text}")
  string(REGEX REPLACE "plant: plant/" "plant: ${_share}/plant/" _text "${_text}")
  string(REGEX REPLACE "\\.\\./build/[a-z-]+/recordings" "/var/lib/selfsensed/recordings" _text "${_text}")
  string(REGEX REPLACE "\\.\\./build/[a-z-]+/control\\.sock" "/run/selfsensed/control.sock" _text "${_text}")
  string(REGEX REPLACE "\\.\\./build/[a-z-]+/selfsensed\\.prom" "/var/lib/selfsensed/selfsensed.prom" _text "${_text}")
  string(REGEX REPLACE " *# relative to this file\n" "\n" _text "${_text}")
  string(REGEX REPLACE " *\\(relative to this file\\)" "" _text "${_text}")
  if(_text MATCHES "\\.\\./build" OR NOT _text MATCHES "model: ${_share}/models/")
    message(FATAL_ERROR "config/${source}: a path the package cannot rewrite (cmake/SelfsensePackage.cmake)")
  endif()
  file(WRITE ${_pkg}/etc/${destination} "${_text}")
endfunction()
selfsense_package_config(selfsensed.yaml selfsensed.yaml)
set(_examples sim.yaml damping-sim.yaml can-sim.yaml modbus-sim.yaml spi-ads131m04.yaml)
foreach(_example IN LISTS _examples)
  selfsense_package_config(${_example} examples/${_example})
endforeach()

# The unit, starting the packaged program.
set_property(DIRECTORY ${PROJECT_SOURCE_DIR} APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
  ${PROJECT_SOURCE_DIR}/systemd/selfsensed.service)
file(READ ${PROJECT_SOURCE_DIR}/systemd/selfsensed.service _unit)
string(REPLACE "ExecStart=/usr/local/bin/selfsensed " "ExecStart=/usr/bin/selfsensed " _unit "${_unit}")
if(NOT _unit MATCHES "\nExecStart=/usr/bin/selfsensed ")
  message(FATAL_ERROR "systemd/selfsensed.service: no ExecStart=/usr/local/bin/selfsensed to point at /usr/bin")
endif()
file(WRITE ${_pkg}/selfsensed.service "${_unit}")

# Changelog (native package: changelog.gz) and copyright, one pair per package.
foreach(_name selfsense libselfsense-dev)
  file(WRITE ${_pkg}/doc/${_name}/changelog
    "${_name} (${_version}) unstable; urgency=medium\n\n"
    "  * Built from the selfsense source tree, commit ${_hash}.\n\n"
    " -- ${_maintainer}  ${_date}\n")
  execute_process(COMMAND gzip -9nf ${_pkg}/doc/${_name}/changelog RESULT_VARIABLE _gzip_rc)
  if(NOT _gzip_rc EQUAL 0)
    message(FATAL_ERROR "gzip of ${_pkg}/doc/${_name}/changelog failed")
  endif()
endforeach()

# The man pages (man/, hand-written; tests/package/check_man.sh keeps them in step with --help),
# compressed as Debian installs them.
foreach(_page selfsense.1 selfsensed.8)
  file(COPY ${PROJECT_SOURCE_DIR}/man/${_page} DESTINATION ${_pkg}/man)
  execute_process(COMMAND gzip -9nf ${_pkg}/man/${_page} RESULT_VARIABLE _gzip_rc)
  if(NOT _gzip_rc EQUAL 0)
    message(FATAL_ERROR "gzip of ${_pkg}/man/${_page} failed")
  endif()
endforeach()

# Conffiles: every file under /etc/selfsense.
set(_conffiles "/etc/selfsense/selfsensed.yaml\n")
foreach(_example IN LISTS _examples)
  string(APPEND _conffiles "/etc/selfsense/examples/${_example}\n")
endforeach()
file(WRITE ${_pkg}/control/conffiles "${_conffiles}")
foreach(_script postinst prerm postrm)
  file(COPY ${PROJECT_SOURCE_DIR}/packaging/debian/${_script} DESTINATION ${_pkg}/control
    FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
endforeach()
# Let a changed maintainer script or configuration reconfigure.
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS
  ${PROJECT_SOURCE_DIR}/systemd/selfsensed.service
  ${PROJECT_SOURCE_DIR}/packaging/debian/postinst ${PROJECT_SOURCE_DIR}/packaging/debian/prerm
  ${PROJECT_SOURCE_DIR}/packaging/debian/postrm ${PROJECT_SOURCE_DIR}/config/selfsensed.yaml
  ${PROJECT_SOURCE_DIR}/man/selfsense.1 ${PROJECT_SOURCE_DIR}/man/selfsensed.8)

set(_system COMPONENT runtime EXCLUDE_FROM_ALL)
install(FILES ${_pkg}/selfsensed.service DESTINATION /lib/systemd/system ${_system})
install(FILES ${PROJECT_SOURCE_DIR}/packaging/debian/selfsense.sysusers DESTINATION /usr/lib/sysusers.d
  RENAME selfsense.conf ${_system})
install(FILES ${PROJECT_SOURCE_DIR}/packaging/debian/60-selfsense.rules DESTINATION /lib/udev/rules.d ${_system})
install(FILES ${_pkg}/etc/selfsensed.yaml DESTINATION /etc/selfsense ${_system})
install(DIRECTORY ${_pkg}/etc/examples DESTINATION /etc/selfsense ${_system})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/models/ DESTINATION ${_share}/models ${_system}
  FILES_MATCHING PATTERN "*.yaml")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/plant/ DESTINATION ${_share}/plant ${_system}
  FILES_MATCHING PATTERN "*.yaml")
install(FILES ${_pkg}/man/selfsense.1.gz DESTINATION /usr/share/man/man1 ${_system})
install(FILES ${_pkg}/man/selfsensed.8.gz DESTINATION /usr/share/man/man8 ${_system})
install(FILES ${_pkg}/doc/selfsense/changelog.gz ${PROJECT_SOURCE_DIR}/packaging/debian/copyright
  DESTINATION /usr/share/doc/selfsense ${_system})
install(FILES ${_pkg}/doc/libselfsense-dev/changelog.gz ${PROJECT_SOURCE_DIR}/packaging/debian/copyright
  DESTINATION /usr/share/doc/libselfsense-dev COMPONENT dev EXCLUDE_FROM_ALL)

# What the packages hold, built without the tests: `cmake --build build --target selfsense_packaged`.
add_custom_target(selfsense_packaged)
add_dependencies(selfsense_packaged ${SELFSENSE_EXPORTED_TARGETS})

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME selfsense)
set(CPACK_PACKAGE_VERSION "${_version}")
set(CPACK_PACKAGE_CONTACT "${_maintainer}")
set(CPACK_PACKAGE_VENDOR "selfsense")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_OUTPUT_FILE_PREFIX packages)  # relative to the directory cpack runs in
set(CPACK_STRIP_FILES ON)
set(CPACK_DEB_COMPONENT_INSTALL ON)
set(CPACK_COMPONENTS_ALL runtime dev)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
# A cross build (cmake/toolchains/) names the target's Debian architecture: the packages'
# Architecture and file names, and the architecture whose libraries dpkg-shlibdeps resolves
# (DEB_HOST_ARCH, set for cpack's children by the project config file). Natively, dpkg's own.
if(SELFSENSE_DEB_ARCH)
  set(CPACK_DEBIAN_PACKAGE_ARCHITECTURE ${SELFSENSE_DEB_ARCH})
  file(WRITE ${_pkg}/cpack-project-config.cmake
    "# Generated by cmake/SelfsensePackage.cmake: dpkg-shlibdeps resolves the target's libraries.\n"
    "set(ENV{DEB_HOST_ARCH} ${SELFSENSE_DEB_ARCH})\n")
  set(CPACK_PROJECT_CONFIG_FILE ${_pkg}/cpack-project-config.cmake)
endif()
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_NAME selfsense)
set(CPACK_DEBIAN_RUNTIME_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_RUNTIME_DESCRIPTION "real-time self-sensing controller for piezo stack actuators
selfsensed controls piezoelectric stack actuators from their own electric
field and charge, reconstructing stress and strain through operator models
of hysteresis and creep, without an external sensor. It runs as a systemd
service (selfsensed.service) as the system user selfsense; the selfsense
tool identifies models, records the simulated transducer and drives the
daemon over its control socket. Installed on the simulated transducer;
edit /etc/selfsense/selfsensed.yaml for a board.")
set(CPACK_DEBIAN_RUNTIME_PACKAGE_CONTROL_EXTRA
  ${_pkg}/control/conffiles ${_pkg}/control/postinst ${_pkg}/control/prerm ${_pkg}/control/postrm)
set(CPACK_DEBIAN_DEV_PACKAGE_NAME libselfsense-dev)
set(CPACK_DEBIAN_DEV_PACKAGE_SECTION libdevel)
set(CPACK_DEBIAN_DEV_PACKAGE_DEPENDS
  "libeigen3-dev (>= 3.4), libyaml-cpp-dev, nlohmann-json3-dev (>= 3.10), libmodbus-dev, libgpiod-dev, libsystemd-dev, pkg-config")
set(CPACK_DEBIAN_DEV_DESCRIPTION "self-sensing piezo controller - development files
Headers, static libraries and the CMake package (find_package(selfsense))
of selfsense: hysteresis and creep operators, transducer models and their
identification, control laws and the real-time loop, for integrators who
link the models into their own programs.")
include(CPack)
