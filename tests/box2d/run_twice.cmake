# Runs the Box2D demo program twice on the same scenario, into two directories, and
# fails unless the traces and summaries are byte for byte identical and the run met its
# expectations.   cmake -DPROGRAM=<box2d_planar> -DWORK_DIR=<dir> -P run_twice.cmake
foreach(var PROGRAM WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_twice.cmake: ${var} is not set")
  endif()
endforeach()
set(scenario circle_gravity)
file(REMOVE_RECURSE ${WORK_DIR})
foreach(run a b)
  execute_process(COMMAND ${PROGRAM} --scenario ${scenario} --no-svg --out ${WORK_DIR}/${run}
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "run ${run} exited with ${rc}:\n${out}\n${err}")
  endif()
endforeach()
foreach(file trace.csv summary.json)
  execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files
                          ${WORK_DIR}/a/${scenario}/${file} ${WORK_DIR}/b/${scenario}/${file}
                  RESULT_VARIABLE differ)
  if(NOT differ EQUAL 0)
    message(FATAL_ERROR "${file} differs between two runs of ${scenario}")
  endif()
endforeach()
file(SIZE ${WORK_DIR}/a/${scenario}/trace.csv size)
message(STATUS "${scenario}: trace.csv (${size} bytes) and summary.json identical across two runs")
