# Helper functions shared by every folder.

# incise_add_library(NAME SOURCES ... DEPS ...)
#   A module library incise_<NAME> with public headers under lib/include, exported and installed
#   as incise::<NAME> (cmake/InciseInstall.cmake installs every target listed in the global
#   property INCISE_LIBRARIES).
function(incise_add_library name)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS" ${ARGN})
  add_library(incise_${name} ${A_SOURCES})
  add_library(incise::${name} ALIAS incise_${name})
  set_target_properties(incise_${name} PROPERTIES EXPORT_NAME ${name})
  target_include_directories(incise_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/lib/include>
                                                   $<INSTALL_INTERFACE:include>)
  target_link_libraries(incise_${name} PUBLIC ${A_DEPS} PRIVATE incise_options)
  set_property(GLOBAL APPEND PROPERTY INCISE_LIBRARIES incise_${name})
endfunction()

# incise_add_gtest(NAME SOURCES ... LIBS ... LABELS ... [TIMEOUT s])
#   A GoogleTest executable; every TEST becomes one ctest case carrying LABELS.
#   Label vocabulary: unit, property, verification, slow, threads (starts threads: run under
#   ThreadSanitizer by ci/test.sh), plus the module name; outside gtest also python, examples
#   and vtk (VTK's own reader, property_tests/io/vtk_readback.py).
function(incise_add_gtest name)
  cmake_parse_arguments(A "" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  if(NOT A_TIMEOUT)
    set(A_TIMEOUT 600)
  endif()
  add_executable(${name} ${A_SOURCES})
  target_link_libraries(${name} PRIVATE ${A_LIBS} incise_test_support GTest::gtest GTest::gtest_main
                                        incise_options)
  target_compile_options(${name} PRIVATE ${INCISE_TEST_DRIVER_FLAGS})
  # gtest_discover_tests (CMake 3.25) flattens PROPERTIES into one list, so a multi-valued
  # LABELS would lose every label after the first. Discover without properties, then apply them
  # from a second ctest include file that runs after the discovered list (<name>_TESTS) is known.
  gtest_discover_tests(${name} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
                       WORKING_DIRECTORY ${PROJECT_SOURCE_DIR} TEST_LIST ${name}_TESTS)
  set(props "${CMAKE_CURRENT_BINARY_DIR}/${name}_properties.cmake")
  file(WRITE "${props}"
       "if(${name}_TESTS)\n"
       "  set_tests_properties(\${${name}_TESTS} PROPERTIES LABELS \"${A_LABELS}\"\n"
       "    TIMEOUT ${A_TIMEOUT} ENVIRONMENT \"INCISE_SOURCE_DIR=${PROJECT_SOURCE_DIR}\")\n"
       "endif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${props}")
  if("threads" IN_LIST A_LABELS)
    set_property(GLOBAL APPEND PROPERTY INCISE_THREADS_TESTS ${name})
  endif()
endfunction()

# incise_add_benchmark(NAME SOURCES ... LIBS ...)
function(incise_add_benchmark name)
  cmake_parse_arguments(A "" "" "SOURCES;LIBS" ${ARGN})
  add_executable(${name} ${A_SOURCES})
  target_link_libraries(${name} PRIVATE ${A_LIBS} incise_bench_support benchmark::benchmark
                                        incise_options)
endfunction()

# incise_add_cli_test(NAME EXIT <status|nonzero> [STDERR <regex>] [USAGE] [STDOUT <regex>]
#                     [STDOUT_NOT <regex>] [WORKDIR <dir>] LABELS ... ARGS ...)
#   Runs `incise ARGS` in the source tree (or in WORKDIR under the current build folder, created
#   empty: for commands that write files) and requires the exit status and, if given, that
#   stderr matches the regex, stdout matches STDOUT and does not match STDOUT_NOT; stderr must be
#   one line unless USAGE (usage text or progress lines follow).
function(incise_add_cli_test name)
  cmake_parse_arguments(A "USAGE" "EXIT;STDERR;STDOUT;STDOUT_NOT;WORKDIR" "ARGS;LABELS" ${ARGN})
  if(NOT TARGET incise)
    return()
  endif()
  set(extra)
  if(DEFINED A_STDERR)
    list(APPEND extra "-DSTDERR_REGEX=${A_STDERR}")
  endif()
  if(DEFINED A_STDOUT)
    list(APPEND extra "-DSTDOUT_REGEX=${A_STDOUT}")
  endif()
  if(DEFINED A_STDOUT_NOT)
    list(APPEND extra "-DSTDOUT_NOT_REGEX=${A_STDOUT_NOT}")
  endif()
  if(A_USAGE)
    list(APPEND extra -DMULTILINE=ON)
  endif()
  set(dir ${PROJECT_SOURCE_DIR})
  if(DEFINED A_WORKDIR)
    set(dir ${CMAKE_CURRENT_BINARY_DIR}/${A_WORKDIR})
    file(MAKE_DIRECTORY ${dir})
  endif()
  add_test(NAME ${name}
           COMMAND ${CMAKE_COMMAND} "-DCMD=$<TARGET_FILE:incise>;${A_ARGS}" -DEXIT=${A_EXIT}
                   ${extra} -P ${PROJECT_SOURCE_DIR}/property_tests/io/cli_expect.cmake
           WORKING_DIRECTORY ${dir})
  set_tests_properties(${name} PROPERTIES LABELS "${A_LABELS}")
endfunction()
