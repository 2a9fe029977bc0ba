# Helper functions shared by every folder.

# incise_add_library(NAME SOURCES ... DEPS ...)
#   A module library incise_<NAME> with public headers under lib/include, exported and installed
#   as incise::<NAME> (cmake/InciseInstall.cmake installs every target listed in the global
#   property INCISE_LIBRARIES).
# Each module library is a CMake unity build of up to INCISE_LIBRARY_UNITY_BATCH sources per
# translation unit (default ON): Eigen's templates and the shared headers are compiled once per
# batch. Measured on the libraries and the CLI (release, compiler cache off, -j2): 306 → 215 s CPU
# (docs/ci.md). A library source must therefore compile after the other sources of its module:
# no file-scope names (anonymous namespaces included) that collide with another file's.
option(INCISE_UNITY_LIBRARIES "Unity-build the module libraries (docs/ci.md)" ON)
set(INCISE_LIBRARY_UNITY_BATCH 8 CACHE STRING "Library sources per unity translation unit")
function(incise_add_library name)
  cmake_parse_arguments(A "" "" "SOURCES;DEPS" ${ARGN})
  add_library(incise_${name} ${A_SOURCES})
  if(INCISE_UNITY_LIBRARIES)
    set_target_properties(incise_${name} PROPERTIES UNITY_BUILD ON
                                                    UNITY_BUILD_BATCH_SIZE ${INCISE_LIBRARY_UNITY_BATCH})
  endif()
  add_library(incise::${name} ALIAS incise_${name})
  set_target_properties(incise_${name} PROPERTIES EXPORT_NAME ${name})
  target_include_directories(incise_${name} PUBLIC $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}/lib/include>
                                                   $<INSTALL_INTERFACE:include>)
  target_link_libraries(incise_${name} PUBLIC ${A_DEPS} PRIVATE incise_options)
  if(INCISE_BUILD_FUZZERS AND name IN_LIST INCISE_FUZZ_COVERAGE_MODULES)
    target_compile_options(incise_${name} PRIVATE -fsanitize=fuzzer-no-link)
  endif()
  set_property(GLOBAL APPEND PROPERTY INCISE_LIBRARIES incise_${name})
endfunction()

# The modules the fuzz harnesses' inputs reach (fuzz/: the mesh readers, the sweep reader, the
# scene parser and builder), compiled with libFuzzer's coverage when INCISE_BUILD_FUZZERS is on.
# The other modules carry ASan + UBSan only: coverage there would guide nothing and made the
# sanitizer build and its tests slower (docs/ci.md).
set(INCISE_FUZZ_COVERAGE_MODULES core mesh io material fem scene)

# incise_add_gtest(NAME SOURCES ... LIBS ... LABELS ... [TIMEOUT s] [OWN_EXECUTABLE])
#   GoogleTest drivers; every TEST becomes one ctest case carrying LABELS.
#   Label vocabulary: unit, property, verification, slow, threads (starts threads: run under
#   ThreadSanitizer by ci/test.sh), plus the module name; outside gtest also python, examples
#   and vtk (VTK's own reader, property_tests/io/vtk_readback.py).
#   With INCISE_GROUP_TESTS (default ON) the drivers of every call with the same LABELS and
#   TIMEOUT share one executable, <labels joined by _>_tests (e.g. property_mesh_tests), unity-
#   built INCISE_TEST_UNITY_BATCH sources per translation unit: Eigen's and GoogleTest's
#   templates are then compiled once per batch instead of once per file, which halves the
#   drivers' compile time (docs/ci.md). NAME becomes an alias of that executable (add_test and
#   $<TARGET_FILE:NAME> work; ctest runs each TEST in its own process either way). A driver
#   file must therefore compile after the other files of its group: no file-scope names that
#   collide with theirs. OWN_EXECUTABLE gives NAME an executable of its own: needed when the
#   caller changes the target afterwards (compile definitions, include folders, dependencies)
#   or runs the whole executable under a test of its own.
option(INCISE_GROUP_TESTS "One unity-built executable per label set of GoogleTest drivers" ON)
set(INCISE_TEST_UNITY_BATCH 6 CACHE STRING "Driver files per unity translation unit (INCISE_GROUP_TESTS)")
function(incise_add_gtest name)
  cmake_parse_arguments(A "OWN_EXECUTABLE" "TIMEOUT" "SOURCES;LIBS;LABELS" ${ARGN})
  set(exe ${name})
  if(INCISE_GROUP_TESTS AND NOT A_OWN_EXECUTABLE)
    string(REPLACE ";" "_" exe "${A_LABELS}")
    if(A_TIMEOUT)
      string(APPEND exe "_timeout${A_TIMEOUT}")
    endif()
    string(APPEND exe "_tests")
  endif()
  if(NOT A_TIMEOUT)
    set(A_TIMEOUT 600)
  endif()
  list(TRANSFORM A_SOURCES PREPEND "${CMAKE_CURRENT_SOURCE_DIR}/" REGEX "^[^/]")
  if(TARGET ${exe})
    target_sources(${exe} PRIVATE ${A_SOURCES})
    target_link_libraries(${exe} PRIVATE ${A_LIBS})
  else()
    add_executable(${exe} ${A_SOURCES})
    target_link_libraries(${exe} PRIVATE ${A_LIBS} incise_test_support GTest::gtest
                                         GTest::gtest_main incise_options)
    target_compile_options(${exe} PRIVATE ${INCISE_TEST_DRIVER_FLAGS})
    if(NOT exe STREQUAL name)
      set_target_properties(${exe} PROPERTIES UNITY_BUILD ON
                                              UNITY_BUILD_BATCH_SIZE ${INCISE_TEST_UNITY_BATCH})
    endif()
    # gtest_discover_tests (CMake 3.25) flattens PROPERTIES into one list, so a multi-valued
    # LABELS would lose every label after the first. Discover without properties, then apply
    # them from a second ctest include file that runs after the discovered list (<exe>_TESTS)
    # is known.
    gtest_discover_tests(${exe} DISCOVERY_MODE PRE_TEST DISCOVERY_TIMEOUT 60
                         WORKING_DIRECTORY ${PROJECT_SOURCE_DIR} TEST_LIST ${exe}_TESTS)
    set(props "${CMAKE_CURRENT_BINARY_DIR}/${exe}_properties.cmake")
    file(WRITE "${props}"
         "if(${exe}_TESTS)\n"
         "  set_tests_properties(\${${exe}_TESTS} PROPERTIES LABELS \"${A_LABELS}\"\n"
         "    TIMEOUT ${A_TIMEOUT} ENVIRONMENT \"INCISE_SOURCE_DIR=${PROJECT_SOURCE_DIR}\")\n"
         "endif()\n")
    set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${props}")
    if("threads" IN_LIST A_LABELS)
      set_property(GLOBAL APPEND PROPERTY INCISE_THREADS_TESTS ${exe})
    endif()
  endif()
  if(NOT exe STREQUAL name)
    add_executable(${name} ALIAS ${exe})
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
