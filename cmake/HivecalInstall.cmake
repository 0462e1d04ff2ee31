# Installable CMake package: find_package(hivecal) gives hivecal::hivecal.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS hivecal EXPORT hivecalTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY lib/include/hivecal DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT hivecalTargets NAMESPACE hivecal:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/hivecal)
configure_package_config_file(cmake/hivecalConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/hivecalConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/hivecal)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/hivecalConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/hivecalConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/hivecalConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/hivecal)
