# Steps of the consumer tests, run as `cmake -DACTION=<action> ... -P driver.cmake`.
#
#   ACTION=install    remove STAGE, then `cmake --install BUILD_DIR --prefix STAGE`
#   ACTION=project    configure, build and run the consumer project SOURCE_DIR in a fresh
#                     BINARY_DIR with the same GENERATOR / MAKE_PROGRAM / CXX_COMPILER;
#                     CACHE_ARGS is a '|'-separated list of extra -D arguments
#   ACTION=compile    compile SOURCE with `CXX_COMPILER FLAGS` ('|'-separated) to OUTPUT,
#                     then run it
#   ACTION=pkgconfig  as compile, with FLAGS taken from `PKG_CONFIG --cflags inhand`
#                     (PKG_CONFIG_PATH = STAGE/DATADIR/pkgconfig); also checks the version
#                     and that the include path is STAGE/INCLUDEDIR. With STRICT=ON:
#                     every other -I of those flags (Eigen's) becomes -isystem, inhand's
#                     stays -I, and WARNING_FLAGS ('|'-separated, with -Werror) are added
#   ACTION=readme     the block of the Markdown file README between <!-- MARKER:begin -->
#                     and <!-- MARKER:end --> (MARKER defaults to tour; without its ```
#                     fences) must equal the file TOUR
cmake_minimum_required(VERSION 3.16)

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " cmd "${ARGN}")
    message(FATAL_ERROR "command failed (${rc}): ${cmd}")
  endif()
endfunction()

function(compile_and_run source output flags)
  get_filename_component(dir "${output}" DIRECTORY)
  file(REMOVE_RECURSE "${dir}")
  file(MAKE_DIRECTORY "${dir}")
  run("${CXX_COMPILER}" ${flags} "${source}" -o "${output}")
  run("${output}")
endfunction()

if(ACTION STREQUAL "install")
  file(REMOVE_RECURSE "${STAGE}")
  run("${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${STAGE}")

elseif(ACTION STREQUAL "project")
  file(REMOVE_RECURSE "${BINARY_DIR}")
  string(REPLACE "|" ";" extra "${CACHE_ARGS}")
  set(make_program)
  if(MAKE_PROGRAM)
    set(make_program "-DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM}")
  endif()
  run("${CMAKE_COMMAND}" -S "${SOURCE_DIR}" -B "${BINARY_DIR}" -G "${GENERATOR}" ${make_program}
      "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}" "-DCMAKE_BUILD_TYPE=${BUILD_TYPE}"
      -DCMAKE_COMPILE_WARNING_AS_ERROR=ON -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF ${extra})
  run("${CMAKE_COMMAND}" --build "${BINARY_DIR}" --config "${BUILD_TYPE}")
  find_program(exe consumer PATHS "${BINARY_DIR}" "${BINARY_DIR}/${BUILD_TYPE}" NO_DEFAULT_PATH)
  if(NOT exe)
    message(FATAL_ERROR "consumer executable not found in ${BINARY_DIR}")
  endif()
  run("${exe}")

elseif(ACTION STREQUAL "compile")
  string(REPLACE "|" ";" flags "${FLAGS}")
  compile_and_run("${SOURCE}" "${OUTPUT}" "${flags}")

elseif(ACTION STREQUAL "pkgconfig")
  set(ENV{PKG_CONFIG_PATH} "${STAGE}/${DATADIR}/pkgconfig")
  execute_process(COMMAND "${PKG_CONFIG}" --modversion inhand
                  OUTPUT_VARIABLE version OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0 OR NOT version STREQUAL EXPECTED_VERSION)
    message(FATAL_ERROR "pkg-config --modversion inhand: '${version}' (${rc}), expected ${EXPECTED_VERSION}")
  endif()
  execute_process(COMMAND "${PKG_CONFIG}" --cflags inhand
                  OUTPUT_VARIABLE cflags OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "pkg-config --cflags inhand failed (${rc})")
  endif()
  message(STATUS "pkg-config --cflags inhand: ${cflags}")
  separate_arguments(flags UNIX_COMMAND "${cflags}")
  # The .pc file is relocatable: its include path must resolve into the staging prefix.
  get_filename_component(expected "${STAGE}/${INCLUDEDIR}" REALPATH)
  set(found FALSE)
  foreach(flag IN LISTS flags)
    if(flag MATCHES "^-I(.+)$")
      get_filename_component(dir "${CMAKE_MATCH_1}" REALPATH)
      if(dir STREQUAL expected)
        set(found TRUE)
      endif()
    endif()
  endforeach()
  if(NOT found)
    message(FATAL_ERROR "pkg-config --cflags inhand (${cflags}) lacks -I${expected}")
  endif()
  if(STRICT)
    # Eigen's headers are not ours to check: a system directory. inhand's stay -I.
    set(strict_flags)
    foreach(flag IN LISTS flags)
      if(flag MATCHES "^-I(.+)$")
        get_filename_component(dir "${CMAKE_MATCH_1}" REALPATH)
        if(NOT dir STREQUAL expected)
          set(flag "-isystem${CMAKE_MATCH_1}")
        endif()
      endif()
      list(APPEND strict_flags "${flag}")
    endforeach()
    string(REPLACE "|" ";" warning_flags "${WARNING_FLAGS}")
    set(flags ${strict_flags} ${warning_flags})
    message(STATUS "compile flags: ${flags}")
  endif()
  compile_and_run("${SOURCE}" "${OUTPUT}" "-std=c++17;${flags}")

elseif(ACTION STREQUAL "readme")
  if(NOT MARKER)
    set(MARKER tour)
  endif()
  set(open_marker "<!-- ${MARKER}:begin -->")
  file(READ "${README}" readme)
  string(FIND "${readme}" "${open_marker}" begin)
  string(FIND "${readme}" "<!-- ${MARKER}:end -->" end)
  if(begin EQUAL -1 OR end EQUAL -1 OR end LESS begin)
    message(FATAL_ERROR "${README}: ${MARKER} markers missing or out of order")
  endif()
  string(LENGTH "${open_marker}" marker_length)
  math(EXPR start "${begin} + ${marker_length}")
  math(EXPR length "${end} - ${start}")
  string(SUBSTRING "${readme}" ${start} ${length} block)
  # Drop the opening fence line (```cpp) and the closing fence (```).
  if(NOT block MATCHES "^[ \t\r\n]*```[a-z+]*\r?\n(.*)\n```[ \t\r\n]*$")
    message(FATAL_ERROR "${README}: the ${MARKER} block is not a single fenced code block")
  endif()
  set(code "${CMAKE_MATCH_1}\n")
  file(READ "${TOUR}" tour)
  if(NOT code STREQUAL tour)
    file(WRITE "${OUTPUT}" "${code}")
    message(FATAL_ERROR "${README}: the ${MARKER} block differs from ${TOUR}; the block is in "
                        "${OUTPUT}: compare them with diff")
  endif()

else()
  message(FATAL_ERROR "unknown ACTION '${ACTION}'")
endif()
