# Install rules and the exported package selfsense::. Two components: `runtime` (the programs;
# with cmake/SelfsensePackage.cmake's system files the Debian package selfsense) and `dev`
# (headers, static libraries, the CMake package: libselfsense-dev). The programs are not in the
# export set, so that the CMake package does not need the programs installed.
include(CMakePackageConfigHelpers)
get_property(SELFSENSE_EXPORTED_TARGETS GLOBAL PROPERTY SELFSENSE_EXPORTED_TARGETS)
set(_selfsense_programs)
set(_selfsense_libraries)
foreach(_target IN LISTS SELFSENSE_EXPORTED_TARGETS)
  get_target_property(_type ${_target} TYPE)
  if(_type STREQUAL "EXECUTABLE")
    list(APPEND _selfsense_programs ${_target})
  else()
    list(APPEND _selfsense_libraries ${_target})
  endif()
endforeach()
install(DIRECTORY include/selfsense DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} COMPONENT dev)
install(TARGETS ${_selfsense_programs} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
install(TARGETS ${_selfsense_libraries} selfsense_build_flags
  EXPORT selfsenseTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT dev
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT selfsenseTargets NAMESPACE selfsense:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/selfsense
  COMPONENT dev)
configure_package_config_file(cmake/selfsenseConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/selfsenseConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/selfsense)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/selfsenseConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/selfsenseConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/selfsenseConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/selfsense COMPONENT dev)
