# cmake -DSOURCE_DIR=<repo> -DPREFIX=<path prefix> -P manifest_sha256.cmake
# Fails unless every row of reference_data/MANIFEST.tsv whose path starts with PREFIX names an
# existing file whose SHA-256 equals the row's sha256 column (reference_data/README.md: "Update
# the sha256 when a file changes"), and at least one row matches PREFIX.
file(STRINGS "${SOURCE_DIR}/reference_data/MANIFEST.tsv" rows)
set(checked 0)
foreach(row IN LISTS rows)
  string(REPLACE "\t" ";" cols "${row}")
  list(GET cols 0 path)
  if(NOT path MATCHES "^${PREFIX}")
    continue()
  endif()
  list(GET cols 1 expected)
  set(file "${SOURCE_DIR}/reference_data/${path}")
  if(NOT EXISTS "${file}")
    message(FATAL_ERROR "MANIFEST.tsv row ${path}: no such file")
  endif()
  file(SHA256 "${file}" actual)
  if(NOT actual STREQUAL expected)
    message(FATAL_ERROR "MANIFEST.tsv row ${path}: sha256 ${expected}, file has ${actual} "
                        "(update the row: sha256sum reference_data/${path})")
  endif()
  math(EXPR checked "${checked} + 1")
endforeach()
if(checked EQUAL 0)
  message(FATAL_ERROR "MANIFEST.tsv has no row under ${PREFIX}")
endif()
message(STATUS "MANIFEST.tsv: ${checked} row(s) under ${PREFIX} match their files")
