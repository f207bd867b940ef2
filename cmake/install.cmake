# Install rules: headers, the static module libraries, the CLI and an exported package
# (find_package(adamesh) -> adamesh::adamesh). Tested by tests/consumer (ctest install.consumer).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

get_property(ADAMESH_MODULES GLOBAL PROPERTY ADAMESH_MODULES)
set(ADAMESH_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/adamesh")
install(TARGETS adamesh adamesh_options ${ADAMESH_MODULES}
        EXPORT adameshTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY include/adamesh DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS adamesh-cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(EXPORT adameshTargets NAMESPACE adamesh:: DESTINATION ${ADAMESH_INSTALL_CMAKEDIR})
configure_package_config_file(cmake/adameshConfig.cmake.in
  "${PROJECT_BINARY_DIR}/adameshConfig.cmake" INSTALL_DESTINATION ${ADAMESH_INSTALL_CMAKEDIR})
# 0.x: minor versions may break the API.
write_basic_package_version_file("${PROJECT_BINARY_DIR}/adameshConfigVersion.cmake"
  COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/adameshConfig.cmake"
              "${PROJECT_BINARY_DIR}/adameshConfigVersion.cmake"
        DESTINATION ${ADAMESH_INSTALL_CMAKEDIR})
