# Install rules and the exported package selfsense::.
include(CMakePackageConfigHelpers)
get_property(SELFSENSE_EXPORTED_TARGETS GLOBAL PROPERTY SELFSENSE_EXPORTED_TARGETS)
install(DIRECTORY include/selfsense DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY drivers/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/selfsense/drivers
  FILES_MATCHING PATTERN "*.hpp")
install(TARGETS ${SELFSENSE_EXPORTED_TARGETS} selfsense_build_flags
  EXPORT selfsenseTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT selfsenseTargets NAMESPACE selfsense:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/selfsense)
configure_package_config_file(cmake/selfsenseConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/selfsenseConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/selfsense)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/selfsenseConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/selfsenseConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/selfsenseConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/selfsense)
