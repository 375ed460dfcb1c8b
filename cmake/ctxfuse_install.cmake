include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS ctxfuse EXPORT ctxfuseTargets)
install(DIRECTORY include/ctxfuse DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT ctxfuseTargets NAMESPACE ctxfuse:: DESTINATION ${CMAKE_INSTALL_DATADIR}/ctxfuse/cmake)
configure_package_config_file(cmake/ctxfuseConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/ctxfuseConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_DATADIR}/ctxfuse/cmake)
# Header-only: any architecture may use the same install.
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/ctxfuseConfigVersion.cmake
  COMPATIBILITY SameMinorVersion ARCH_INDEPENDENT)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/ctxfuseConfig.cmake
              ${CMAKE_CURRENT_BINARY_DIR}/ctxfuseConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_DATADIR}/ctxfuse/cmake)
