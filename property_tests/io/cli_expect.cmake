# ctest helper: run CMD (a ;-list) and require exit status EXIT (a number or "nonzero"), that
# stderr matches STDERR_REGEX (if given) and is one line (unless MULTILINE, for usage text or
# progress), that stdout matches STDOUT_REGEX and does not match STDOUT_NOT_REGEX (if given).
#   cmake -DCMD=... -DEXIT=nonzero -DSTDERR_REGEX=... [-DMULTILINE=ON] [-DSTDOUT_REGEX=...]
#         [-DSTDOUT_NOT_REGEX=...] -P cli_expect.cmake
execute_process(COMMAND ${CMD} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message(STATUS "exit ${rc}\n${out}\nstderr: ${err}")
if(EXIT STREQUAL "nonzero")
  if(rc EQUAL 0)
    message(FATAL_ERROR "expected a non-zero exit status")
  endif()
elseif(NOT rc EQUAL EXIT)
  message(FATAL_ERROR "expected exit status ${EXIT}, got ${rc}")
endif()
if(DEFINED STDERR_REGEX AND NOT err MATCHES "${STDERR_REGEX}")
  message(FATAL_ERROR "stderr does not match '${STDERR_REGEX}'")
endif()
string(REGEX MATCHALL "\n" lines "${err}")
list(LENGTH lines n)
if(n GREATER 1 AND NOT MULTILINE)
  message(FATAL_ERROR "stderr has ${n} lines; expected at most one")
endif()
if(DEFINED STDOUT_REGEX AND NOT out MATCHES "${STDOUT_REGEX}")
  message(FATAL_ERROR "stdout does not match '${STDOUT_REGEX}'")
endif()
if(DEFINED STDOUT_NOT_REGEX AND out MATCHES "${STDOUT_NOT_REGEX}")
  message(FATAL_ERROR "stdout matches '${STDOUT_NOT_REGEX}' ('${CMAKE_MATCH_0}'); it must not")
endif()
