# ctest driver for `incise run`: runs INCISE with ARGS in WORKDIR (emptied first) and checks the
# exit code (EXPECT_RC), that EXPECT_FILE exists (if given) and that WORKDIR holds no file at all
# when EXPECT_EMPTY is set (a rejected scene must write nothing); EXPECT_MESSAGE / EXPECT_OUTPUT:
# regular expressions stderr / stdout must match.
file(REMOVE_RECURSE "${WORKDIR}")
file(MAKE_DIRECTORY "${WORKDIR}")
separate_arguments(arg_list UNIX_COMMAND "${ARGS}")
execute_process(COMMAND "${INCISE}" ${arg_list} WORKING_DIRECTORY "${WORKDIR}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(NOT rc EQUAL EXPECT_RC)
  message(FATAL_ERROR "exit code ${rc}, expected ${EXPECT_RC}")
endif()
if(EXPECT_FILE AND NOT EXISTS "${WORKDIR}/${EXPECT_FILE}")
  message(FATAL_ERROR "missing output ${EXPECT_FILE}")
endif()
if(EXPECT_MESSAGE AND NOT err MATCHES "${EXPECT_MESSAGE}")
  message(FATAL_ERROR "stderr does not match '${EXPECT_MESSAGE}'")
endif()
if(EXPECT_OUTPUT AND NOT out MATCHES "${EXPECT_OUTPUT}")
  message(FATAL_ERROR "stdout does not match '${EXPECT_OUTPUT}'")
endif()
if(EXPECT_EMPTY)
  file(GLOB_RECURSE written "${WORKDIR}/*")
  if(written)
    message(FATAL_ERROR "a rejected scene wrote files: ${written}")
  endif()
endif()
