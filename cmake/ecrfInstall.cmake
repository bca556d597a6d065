# The CMake package (find_package(ecrf CONFIG): ecrf::decoder, ecrf::trainer) and ecrf-decoder.pc.
include(CMakePackageConfigHelpers)
set(ECRF_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/ecrf)

install(EXPORT ecrfTargets NAMESPACE ecrf:: DESTINATION ${ECRF_CMAKE_DIR})
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/ecrfConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/ecrfConfig.cmake
                              INSTALL_DESTINATION ${ECRF_CMAKE_DIR})
# 0.x: a minor release may break the ABI (see the SOVERSION), so only the same minor matches.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(ECRF_COMPATIBILITY SameMinorVersion)
else()
  set(ECRF_COMPATIBILITY SameMajorVersion)
endif()
write_basic_package_version_file(${PROJECT_BINARY_DIR}/ecrfConfigVersion.cmake
                                 COMPATIBILITY ${ECRF_COMPATIBILITY})
install(FILES ${PROJECT_BINARY_DIR}/ecrfConfig.cmake ${PROJECT_BINARY_DIR}/ecrfConfigVersion.cmake
        DESTINATION ${ECRF_CMAKE_DIR})

# Relative to the .pc file, so an installed tree can be moved (pkg-config sets ${pcfiledir}).
set(ECRF_PC_DIR ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
file(RELATIVE_PATH ECRF_PC_PREFIX /${ECRF_PC_DIR} /)
string(REGEX REPLACE "/$" "" ECRF_PC_PREFIX "\${pcfiledir}/${ECRF_PC_PREFIX}")
configure_file(${CMAKE_CURRENT_LIST_DIR}/ecrf-decoder.pc.in ${PROJECT_BINARY_DIR}/ecrf-decoder.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/ecrf-decoder.pc DESTINATION ${ECRF_PC_DIR})
