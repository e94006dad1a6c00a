# Consumer tests: inhand used the three ways README.md documents, each in its own
# binary directory under <build>/tests/consumer/, with the compiler of this build.
#   consumer.install           (fixture) cmake --install this build into a staging prefix
#   consumer.find_package      find_package(inhand CONFIG REQUIRED) from the staging prefix
#   consumer.pkg_config        pkg-config --cflags inhand from the staging prefix, compile, run
#   consumer.pkg_config_strict      the same with -Wall -Wextra -Wconversion -Wsign-conversion
#                              -Werror (Eigen as a system directory, inhand not): the
#                              controller in double and float (strict/main.cpp)
#   consumer.pkg_config_strict_sim  the same for the simulator (strict/sim_main.cpp)
#   consumer.pkg_config_readme_tour the same for docs/tour.md's whole-hand loop, against
#                              the installed prefix (readme_tour.cpp)
#   consumer.add_subdirectory  add_subdirectory(<repo> inhand); subproject options OFF
#   consumer.header_dropin     c++ -std=c++17 -I include -I <eigen> only
#   consumer.readme_tour       docs/tour.md's whole-hand loop, compiled and run
#   consumer.readme_tour_in_sync  docs/tour.md's tour block == readme_tour.cpp
#   consumer.readme_allegro_in_sync  README.md's first program (allegro block) ==
#                              examples/05_allegro_urdf/main.cpp (run as example.05_allegro_urdf)
# and example.<name>, which runs examples/<name>.cpp (finger_tracking, 01_finger_servo,
# 02_whole_hand, 03_external_kinematics, 04_planar_hand); each exits non-zero unless its
# own check passed.
set(INHAND_CONSUMER_SRC ${CMAKE_CURRENT_LIST_DIR})
set(INHAND_CONSUMER_BIN ${CMAKE_CURRENT_BINARY_DIR}/consumer)
set(INHAND_CONSUMER_DRIVER ${INHAND_CONSUMER_SRC}/driver.cmake)
set(INHAND_CONSUMER_STAGE ${INHAND_CONSUMER_BIN}/stage)
if(CMAKE_BUILD_TYPE)
  set(INHAND_CONSUMER_BUILD_TYPE ${CMAKE_BUILD_TYPE})
else()
  set(INHAND_CONSUMER_BUILD_TYPE Release)
endif()
get_target_property(INHAND_EIGEN_INCLUDE_DIRS Eigen3::Eigen INTERFACE_INCLUDE_DIRECTORIES)

# Arguments shared by the two consumer CMake projects.
set(INHAND_CONSUMER_PROJECT_ARGS
  -DGENERATOR=${CMAKE_GENERATOR}
  -DMAKE_PROGRAM=${CMAKE_MAKE_PROGRAM}
  -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
  -DBUILD_TYPE=${INHAND_CONSUMER_BUILD_TYPE})

if(INHAND_INSTALL)
  add_test(NAME consumer.install
    COMMAND ${CMAKE_COMMAND} -DACTION=install -DBUILD_DIR=${PROJECT_BINARY_DIR}
            -DSTAGE=${INHAND_CONSUMER_STAGE} -P ${INHAND_CONSUMER_DRIVER})
  set_tests_properties(consumer.install PROPERTIES FIXTURES_SETUP inhand_staged_install)

  add_test(NAME consumer.find_package
    COMMAND ${CMAKE_COMMAND} -DACTION=project ${INHAND_CONSUMER_PROJECT_ARGS}
            -DSOURCE_DIR=${INHAND_CONSUMER_SRC}/find_package
            -DBINARY_DIR=${INHAND_CONSUMER_BIN}/find_package
            "-DCACHE_ARGS=-DCMAKE_PREFIX_PATH=${INHAND_CONSUMER_STAGE}|-DEigen3_DIR=${Eigen3_DIR}|-DINHAND_EXPECTED_PREFIX=${INHAND_CONSUMER_STAGE}"
            -P ${INHAND_CONSUMER_DRIVER})
  set_tests_properties(consumer.find_package PROPERTIES FIXTURES_REQUIRED inhand_staged_install)

  find_program(INHAND_PKG_CONFIG pkg-config)
  if(INHAND_PKG_CONFIG)
    add_test(NAME consumer.pkg_config
      COMMAND ${CMAKE_COMMAND} -DACTION=pkgconfig -DPKG_CONFIG=${INHAND_PKG_CONFIG}
              -DSTAGE=${INHAND_CONSUMER_STAGE} -DDATADIR=${CMAKE_INSTALL_DATADIR}
              -DINCLUDEDIR=${CMAKE_INSTALL_INCLUDEDIR} -DEXPECTED_VERSION=${PROJECT_VERSION}
              -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
              -DSOURCE=${INHAND_CONSUMER_SRC}/dropin/main.cpp
              -DOUTPUT=${INHAND_CONSUMER_BIN}/pkg_config/consumer
              -P ${INHAND_CONSUMER_DRIVER})
    set_tests_properties(consumer.pkg_config PROPERTIES FIXTURES_REQUIRED inhand_staged_install)
    if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
      foreach(case "strict|strict/main" "strict_sim|strict/sim_main" "readme_tour|readme_tour")
        string(REPLACE "|" ";" parts "${case}")
        list(GET parts 0 name)
        list(GET parts 1 source)
        add_test(NAME consumer.pkg_config_${name}
          COMMAND ${CMAKE_COMMAND} -DACTION=pkgconfig -DPKG_CONFIG=${INHAND_PKG_CONFIG}
                  -DSTAGE=${INHAND_CONSUMER_STAGE} -DDATADIR=${CMAKE_INSTALL_DATADIR}
                  -DINCLUDEDIR=${CMAKE_INSTALL_INCLUDEDIR} -DEXPECTED_VERSION=${PROJECT_VERSION}
                  -DCXX_COMPILER=${CMAKE_CXX_COMPILER} -DSTRICT=ON
                  "-DWARNING_FLAGS=-Wall|-Wextra|-Wconversion|-Wsign-conversion|-Werror"
                  -DSOURCE=${INHAND_CONSUMER_SRC}/${source}.cpp
                  -DOUTPUT=${INHAND_CONSUMER_BIN}/pkg_config_${name}/consumer
                  -P ${INHAND_CONSUMER_DRIVER})
        set_tests_properties(consumer.pkg_config_${name} PROPERTIES
          FIXTURES_REQUIRED inhand_staged_install LABELS consumer TIMEOUT 300)
      endforeach()
    endif()
  else()
    message(STATUS "pkg-config not found: consumer.pkg_config is not run")
  endif()
endif()

add_test(NAME consumer.add_subdirectory
  COMMAND ${CMAKE_COMMAND} -DACTION=project ${INHAND_CONSUMER_PROJECT_ARGS}
          -DSOURCE_DIR=${INHAND_CONSUMER_SRC}/add_subdirectory
          -DBINARY_DIR=${INHAND_CONSUMER_BIN}/add_subdirectory
          "-DCACHE_ARGS=-DINHAND_SOURCE_DIR=${PROJECT_SOURCE_DIR}|-DEigen3_DIR=${Eigen3_DIR}"
          -P ${INHAND_CONSUMER_DRIVER})

set(INHAND_EIGEN_INCLUDE_FLAGS)
foreach(dir IN LISTS INHAND_EIGEN_INCLUDE_DIRS)
  string(APPEND INHAND_EIGEN_INCLUDE_FLAGS "|-I|${dir}")
endforeach()
add_test(NAME consumer.header_dropin
  COMMAND ${CMAKE_COMMAND} -DACTION=compile -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
          "-DFLAGS=-std=c++17|-I|${PROJECT_SOURCE_DIR}/include${INHAND_EIGEN_INCLUDE_FLAGS}"
          -DSOURCE=${INHAND_CONSUMER_SRC}/dropin/main.cpp
          -DOUTPUT=${INHAND_CONSUMER_BIN}/header_dropin/consumer
          -P ${INHAND_CONSUMER_DRIVER})

# The core's whole-hand loop (docs/tour.md) compiles as written and checks its own result.
add_executable(consumer_readme_tour ${INHAND_CONSUMER_SRC}/readme_tour.cpp)
target_link_libraries(consumer_readme_tour PRIVATE inhand::inhand inhand_warnings)
add_test(NAME consumer.readme_tour COMMAND consumer_readme_tour)
add_test(NAME consumer.readme_tour_in_sync
  COMMAND ${CMAKE_COMMAND} -DACTION=readme -DREADME=${PROJECT_SOURCE_DIR}/docs/tour.md
          -DTOUR=${INHAND_CONSUMER_SRC}/readme_tour.cpp
          -DOUTPUT=${INHAND_CONSUMER_BIN}/readme_tour_from_readme.cpp
          -P ${INHAND_CONSUMER_DRIVER})
# The README's first program is the Allegro example, word for word.
add_test(NAME consumer.readme_allegro_in_sync
  COMMAND ${CMAKE_COMMAND} -DACTION=readme -DMARKER=allegro -DREADME=${PROJECT_SOURCE_DIR}/README.md
          -DTOUR=${PROJECT_SOURCE_DIR}/examples/05_allegro_urdf/main.cpp
          -DOUTPUT=${INHAND_CONSUMER_BIN}/allegro_from_readme.cpp
          -P ${INHAND_CONSUMER_DRIVER})

set_tests_properties(consumer.add_subdirectory consumer.header_dropin consumer.readme_tour
  consumer.readme_tour_in_sync consumer.readme_allegro_in_sync PROPERTIES LABELS consumer
  TIMEOUT 300)
if(INHAND_INSTALL)
  set_tests_properties(consumer.install consumer.find_package PROPERTIES LABELS consumer
    TIMEOUT 300)
  if(INHAND_PKG_CONFIG)
    set_tests_properties(consumer.pkg_config PROPERTIES LABELS consumer TIMEOUT 300)
  endif()
endif()

# The examples are consumers too: each exits non-zero unless its own check passed
# (finger_tracking: it converged; 01_..04_: see the file comment of each). The
# URDF example 05_allegro_urdf registers its own test (examples/05_allegro_urdf).
# (Examples are added after the tests, so the targets cannot be tested for here.)
if(INHAND_BUILD_EXAMPLES)
  foreach(example finger_tracking 01_finger_servo 02_whole_hand 03_external_kinematics
                  04_planar_hand)
    if(EXISTS ${PROJECT_SOURCE_DIR}/examples/${example}.cpp)
      add_test(NAME example.${example} COMMAND ${example})
      set_tests_properties(example.${example} PROPERTIES LABELS example TIMEOUT 120)
    endif()
  endforeach()
endif()
