# Installation and export of the incise package (docs/install.md):
#   <prefix>/include/incise/...                   public headers (lib/include/incise)
#   <prefix>/lib/libincise_<module>.a             every module library (INCISE_LIBRARIES)
#   <prefix>/bin/incise                           the command-line program
#   <prefix>/lib/cmake/incise/                    inciseConfig.cmake, inciseConfigVersion.cmake,
#                                                 inciseTargets*.cmake (namespace incise::), and
#                                                 the find modules of CHOLMOD and FFTW3
#   <prefix>/lib/pkgconfig/incise.pc              pkg-config file (relocatable: ${pcfiledir})
#   <prefix>/share/incise/                        run-time data: reference_data/ without fuzz/
# The build tree is a package too: find_package(incise) with incise_DIR=<build>/cmake/incise
# (data: the source tree's reference_data).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

get_property(incise_libraries GLOBAL PROPERTY INCISE_LIBRARIES)
set(incise_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/incise)
set(incise_data_dir ${CMAKE_INSTALL_DATADIR}/incise)

# incise_options (warnings, INCISE_PARANOID) is a private link dependency of every library; CMake
# (3.25) requires it in the export set of static libraries, where it appears only as
# $<LINK_ONLY:incise::options>, so consumers get none of its compile options.
set_target_properties(incise_options PROPERTIES EXPORT_NAME options)
install(TARGETS ${incise_libraries} incise_options EXPORT inciseTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
if(TARGET incise)
  install(TARGETS incise EXPORT inciseTargets RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/lib/include/incise
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR} FILES_MATCHING PATTERN "*.hpp")
install(DIRECTORY ${PROJECT_SOURCE_DIR}/reference_data/
        DESTINATION ${incise_data_dir} PATTERN "fuzz" EXCLUDE)

# `cmake --build --preset release --target incise_package` builds exactly what `cmake --install`
# installs (ci/demo.sh), without the tests and benchmarks (python/CMakeLists.txt adds the module).
add_custom_target(incise_package)
add_dependencies(incise_package ${incise_libraries})
if(TARGET incise)
  add_dependencies(incise_package incise)
endif()

install(EXPORT inciseTargets NAMESPACE incise:: DESTINATION ${incise_cmake_dir})
set(incise_build_package_dir ${PROJECT_BINARY_DIR}/cmake/incise)
export(EXPORT inciseTargets NAMESPACE incise::
       FILE ${incise_build_package_dir}/inciseTargets.cmake)

# inciseConfig.cmake: once for the install tree (data under <prefix>/share/incise), once for the
# build tree (data: the source tree's reference_data).
set(INCISE_CONFIG_DATA_DIR ${incise_data_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/inciseConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/cmake/install/inciseConfig.cmake
                              INSTALL_DESTINATION ${incise_cmake_dir}
                              PATH_VARS INCISE_CONFIG_DATA_DIR)
set(INCISE_CONFIG_DATA_DIR ${PROJECT_SOURCE_DIR}/reference_data)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/inciseConfig.cmake.in
                              ${incise_build_package_dir}/inciseConfig.cmake
                              INSTALL_DESTINATION ${incise_build_package_dir}
                              INSTALL_PREFIX ${PROJECT_BINARY_DIR}
                              PATH_VARS INCISE_CONFIG_DATA_DIR)
# 0.x: a minor version may break the API, so only the same major.minor is compatible.
write_basic_package_version_file(${incise_build_package_dir}/inciseConfigVersion.cmake
                                 VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
foreach(module FindCHOLMOD FindFFTW3)
  configure_file(${PROJECT_SOURCE_DIR}/cmake/${module}.cmake
                 ${incise_build_package_dir}/${module}.cmake COPYONLY)
endforeach()
install(FILES ${PROJECT_BINARY_DIR}/cmake/install/inciseConfig.cmake
              ${incise_build_package_dir}/inciseConfigVersion.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindCHOLMOD.cmake
              ${PROJECT_SOURCE_DIR}/cmake/FindFFTW3.cmake
        DESTINATION ${incise_cmake_dir})

# incise.pc. The libraries are static, so Libs names every module (dependents first) and the
# libraries they need: SuiteSparse (no .pc on Debian: the paths FindCHOLMOD found) and threads;
# Eigen, nlohmann_json, FFTW and zlib come through Requires.
set(incise_pc_libs "-L\${libdir}")
list(REVERSE incise_libraries)
foreach(lib ${incise_libraries})
  string(APPEND incise_pc_libs " -l${lib}")
endforeach()
foreach(path ${CHOLMOD_LIBRARY} ${AMD_LIBRARY} ${COLAMD_LIBRARY} ${CAMD_LIBRARY}
             ${CCOLAMD_LIBRARY} ${SUITESPARSECONFIG_LIBRARY})
  get_filename_component(dir ${path} DIRECTORY)
  get_filename_component(name ${path} NAME_WE)
  string(REGEX REPLACE "^lib" "" name ${name})
  if(NOT dir IN_LIST CMAKE_CXX_IMPLICIT_LINK_DIRECTORIES AND NOT " ${incise_pc_libs} " MATCHES " -L${dir} ")
    string(APPEND incise_pc_libs " -L${dir}")
  endif()
  string(APPEND incise_pc_libs " -l${name}")
endforeach()
if(CMAKE_THREAD_LIBS_INIT)
  string(APPEND incise_pc_libs " ${CMAKE_THREAD_LIBS_INIT}")
endif()
# prefix relative to <prefix>/<libdir>/pkgconfig, so that the installed tree can be moved.
file(RELATIVE_PATH incise_pc_prefix /p/${CMAKE_INSTALL_LIBDIR}/pkgconfig /p)
string(REGEX REPLACE "/$" "" incise_pc_prefix "${incise_pc_prefix}")
configure_file(${PROJECT_SOURCE_DIR}/cmake/incise.pc.in ${PROJECT_BINARY_DIR}/cmake/install/incise.pc
               @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/cmake/install/incise.pc
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
