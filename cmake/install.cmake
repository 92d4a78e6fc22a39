# Install headers under include/mppi/<folder>/, the libraries, the data files and an exported
# package so that an out-of-tree project can do find_package(mppi) and link mppi::core etc.
include(CMakePackageConfigHelpers)

foreach(folder IN ITEMS base mppi dynamics costs factory sim chassis plot)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${folder}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/mppi/${folder}
          FILES_MATCHING PATTERN "*.hpp")
endforeach()
install(FILES ${MPPI_GENERATED_DIR}/dynamics/model_list.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/mppi/dynamics)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/ DESTINATION ${CMAKE_INSTALL_DATADIR}/mppi/data)

install(TARGETS mppi_core mppi_io mppi_plot mppi_sim mppi_chassis mppi_warnings EXPORT mppiTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(EXPORT mppiTargets NAMESPACE mppi:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/mppi)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/mppiConfig.cmake.in
  ${PROJECT_BINARY_DIR}/mppiConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/mppi)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/mppiConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/mppiConfig.cmake ${PROJECT_BINARY_DIR}/mppiConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/mppi_installed_data_dir.cpp.in
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/mppi)

# The estimation part (sysid/), the evidence generator (evidence/) and the sim-vs-real diagnosis
# (diagnose/), when built: their headers and libraries join the package.
foreach(part sysid evidence diagnose)
  if(TARGET mppi_${part})
    install(DIRECTORY ${PROJECT_SOURCE_DIR}/${part}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/mppi/${part}
            FILES_MATCHING PATTERN "*.hpp")
    install(TARGETS mppi_${part} EXPORT mppiTargets
            ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
            LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
  endif()
endforeach()
