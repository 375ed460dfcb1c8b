# Install rules and the CMake package for find_package(ctxfuse CONFIG). Included from the
# top-level CMakeLists.txt after the ctxfuse target is defined (and after GNUInstallDirs,
# which the target's install include directory depends on).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(ctxfuse_package_dir ${CMAKE_INSTALL_DATADIR}/ctxfuse/cmake)

install(TARGETS ctxfuse EXPORT ctxfuseTargets)
# Not include/ctxfuse/instances/: those headers declare what the build-tree-only compiled target
# ctxfuse::instances (src/) defines.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/ctxfuse
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp"
        PATTERN "instances" EXCLUDE)
install(EXPORT ctxfuseTargets NAMESPACE ctxfuse:: DESTINATION ${ctxfuse_package_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/ctxfuseConfig.cmake.in
  ${PROJECT_BINARY_DIR}/ctxfuseConfig.cmake
  INSTALL_DESTINATION ${ctxfuse_package_dir})
# Header-only: one install serves every architecture. 0.x releases promise nothing across
# minor versions, hence SameMinorVersion.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ctxfuseConfigVersion.cmake
  COMPATIBILITY SameMinorVersion ARCH_INDEPENDENT)
install(FILES ${PROJECT_BINARY_DIR}/ctxfuseConfig.cmake
              ${PROJECT_BINARY_DIR}/ctxfuseConfigVersion.cmake
        DESTINATION ${ctxfuse_package_dir})
