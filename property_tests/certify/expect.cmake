# expect(WHAT RC OUT_REGEX ERR_REGEX COMMAND...): runs COMMAND in WORKDIR and fails the calling
# ctest script unless the exit status is RC and stdout / stderr match the regexes. Included by
# data_lookup.cmake and bench_cli.cmake.
function(expect what rc_expected out_regex err_regex)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY "${WORKDIR}" RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message(STATUS "${what}: exit ${rc}\n${out}stderr: ${err}")
  if(NOT rc EQUAL rc_expected)
    message(FATAL_ERROR "${what}: exit ${rc}, expected ${rc_expected}")
  endif()
  if(NOT out MATCHES "${out_regex}")
    message(FATAL_ERROR "${what}: stdout does not match '${out_regex}'")
  endif()
  if(NOT err MATCHES "${err_regex}")
    message(FATAL_ERROR "${what}: stderr does not match '${err_regex}'")
  endif()
endfunction()
