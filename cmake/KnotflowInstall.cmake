# `cmake --install <build> [--prefix <dir>]`: the programs (src/app), the libraries, their Fortran
# modules (include/knotflow; .mod files only fit the compiler that built them), and an exported
# CMake package, so that another project can
#     find_package(knotflow 0.1 REQUIRED)      # with -DCMAKE_PREFIX_PATH=<prefix>
#     target_link_libraries(app PRIVATE knotflow::knotflow_lib)   # + knotflow::knotflow_parallel
# tests/package builds such a project against an installation.
include(CMakePackageConfigHelpers)
set(KNOTFLOW_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/knotflow)

install(TARGETS knotflow_lib knotflow_parallel EXPORT knotflowTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${KNOTFLOW_INSTALL_MODDIR})
# Every module of the libraries is named kf_* (the tests' modules, test_*, share the directory).
install(DIRECTORY ${CMAKE_Fortran_MODULE_DIRECTORY}/ DESTINATION ${KNOTFLOW_INSTALL_MODDIR}
  FILES_MATCHING PATTERN "kf_*.mod")
install(EXPORT knotflowTargets NAMESPACE knotflow:: FILE knotflowTargets.cmake
  DESTINATION ${KNOTFLOW_INSTALL_CMAKEDIR})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/knotflowConfig.cmake.in
  ${PROJECT_BINARY_DIR}/knotflowConfig.cmake
  INSTALL_DESTINATION ${KNOTFLOW_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/knotflowConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/knotflowConfig.cmake ${PROJECT_BINARY_DIR}/knotflowConfigVersion.cmake
  DESTINATION ${KNOTFLOW_INSTALL_CMAKEDIR})
