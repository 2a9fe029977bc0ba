# `cmake --build --preset release --target incise_docs`: the API reference of the public headers
# (lib/include/incise/) with Doxygen (Debian `doxygen`), HTML in <build>/docs/api/html/index.html.
# Any Doxygen warning fails the target (WARN_AS_ERROR=FAIL_ON_WARNINGS): malformed commands,
# unknown HTML tags (write `<id>` in backticks), broken references. Undocumented members are not
# warned about (WARN_IF_UNDOCUMENTED=NO): about 330 have no `///` comment of their own yet
# (Doxygen 1.9.4; reported, not asserted) — operators of core/simd_scalar.hpp, members of the
# material models' energy structs, constructors of the error classes, ...
# ci/test.sh builds the target in stage 1. The target is absent when Doxygen is not installed.
find_package(Doxygen QUIET)
if(NOT DOXYGEN_FOUND)
  return()
endif()
set(DOXYGEN_PROJECT_NAME incise)
set(DOXYGEN_PROJECT_NUMBER ${PROJECT_VERSION})
set(DOXYGEN_PROJECT_BRIEF "Interactive finite-element simulation of soft tissue")
set(DOXYGEN_OUTPUT_DIRECTORY ${PROJECT_BINARY_DIR}/docs/api)
set(DOXYGEN_FILE_PATTERNS *.hpp)
set(DOXYGEN_RECURSIVE YES)
set(DOXYGEN_STRIP_FROM_PATH ${PROJECT_SOURCE_DIR}/lib/include)
set(DOXYGEN_STRIP_FROM_INC_PATH ${PROJECT_SOURCE_DIR}/lib/include)
set(DOXYGEN_FULL_PATH_NAMES YES)
set(DOXYGEN_GENERATE_HTML YES)
set(DOXYGEN_GENERATE_LATEX NO)
set(DOXYGEN_HAVE_DOT NO)
set(DOXYGEN_QUIET YES)
set(DOXYGEN_WARNINGS YES)
set(DOXYGEN_WARN_IF_UNDOCUMENTED NO)
set(DOXYGEN_WARN_IF_DOC_ERROR YES)
set(DOXYGEN_WARN_AS_ERROR FAIL_ON_WARNINGS)
set(DOXYGEN_EXCLUDE_SYMBOLS detail)
doxygen_add_docs(incise_docs ${PROJECT_SOURCE_DIR}/lib/include/incise
                 COMMENT "incise: API reference (Doxygen) in ${DOXYGEN_OUTPUT_DIRECTORY}/html")
