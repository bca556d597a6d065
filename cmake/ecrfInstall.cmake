# The CMake package (find_package(ecrf CONFIG): ecrf::decoder, ecrf::trainer) and ecrf-decoder.pc.
include(CMakePackageConfigHelpers)
set(ECRF_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/ecrf)

if(ECRF_BUILD_TRAINER)
  # ecrf::trainer is an interface over the trainer's and the encoder's static libraries; they are
  # installed with it. Their headers include decoder/ and format/ internals and are installed
  # beside them under include/ecrf-trainer (not a stable API, unlike ecrf/decoder.h).
  get_property(ECRF_TRAINER_LIBRARIES GLOBAL PROPERTY ECRF_TRAINER_LIBRARIES)
  install(TARGETS ecrf_trainer ${ECRF_TRAINER_LIBRARIES} ecrf_format_encoder EXPORT ecrfTargets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  foreach(dir trainer/data trainer/scenes trainer/model trainer/rate trainer/train encoder decoder format format/entropy format/coefficients)
    # *.def: tables the headers expand (trainer/train/train_fields.def).
    file(GLOB headers ${PROJECT_SOURCE_DIR}/${dir}/*.h ${PROJECT_SOURCE_DIR}/${dir}/*.def)
    install(FILES ${headers} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/ecrf-trainer/${dir})
  endforeach()
endif()

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
