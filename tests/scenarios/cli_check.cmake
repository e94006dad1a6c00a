# Runs inhand_scenario and checks its exit status, its output and the files it leaves.
#   -DEXE=<inhand_scenario> -DSCENARIO=<file> -DOUT_DIR=<dir> -DEXPECT_EXIT=<n>
#   -DEXPECT_OUTPUT=<regex>            must match stdout + stderr
#   -DEXPECT_FILES=ON|OFF              OUT_DIR holds trace.csv and summary.json (ON) or
#                                      nothing at all (OFF: a failed run writes nothing)
#   -DTABLE_EXIT=<n> -DTABLE_OUTPUT=<regex>  optional: then `--table OUT_DIR/summary.json
#                                      --check` must exit TABLE_EXIT and print TABLE_OUTPUT
file(REMOVE_RECURSE ${OUT_DIR})
execute_process(COMMAND ${EXE} ${SCENARIO} --out ${OUT_DIR} --check
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("exit ${rc}\n--- stdout\n${out}--- stderr\n${err}")
if(NOT rc EQUAL EXPECT_EXIT)
  message(FATAL_ERROR "expected exit status ${EXPECT_EXIT}, got ${rc}")
endif()
if(NOT "${out}${err}" MATCHES "${EXPECT_OUTPUT}")
  message(FATAL_ERROR "output does not match '${EXPECT_OUTPUT}'")
endif()
file(GLOB left ${OUT_DIR}/* ${OUT_DIR}/.*)
if(EXPECT_FILES)
  foreach(f trace.csv summary.json)
    if(NOT EXISTS ${OUT_DIR}/${f})
      message(FATAL_ERROR "${OUT_DIR}/${f} was not written")
    endif()
  endforeach()
  list(LENGTH left n)
  if(NOT n EQUAL 2)
    message(FATAL_ERROR "unexpected files in ${OUT_DIR}: ${left}")
  endif()
elseif(left)
  message(FATAL_ERROR "a failed run left output behind: ${left}")
endif()
if(DEFINED TABLE_EXIT)
  execute_process(COMMAND ${EXE} --table ${OUT_DIR}/summary.json --check
    RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  message("--table: exit ${rc}\n${out}${err}")
  if(NOT rc EQUAL TABLE_EXIT)
    message(FATAL_ERROR "--table: expected exit status ${TABLE_EXIT}, got ${rc}")
  endif()
  if(NOT "${out}${err}" MATCHES "${TABLE_OUTPUT}")
    message(FATAL_ERROR "--table: output does not match '${TABLE_OUTPUT}'")
  endif()
endif()
