# The packages the URDF reader, the tests, benchmarks and examples use (the core
# library itself needs only Eigen). Each is looked for once, here, when a part that uses
# it is enabled; where one is missing the parts that need it are skipped with a message
# naming the package, or, with INHAND_REQUIRE_ALL_DEPENDENCIES=ON (scripts/test, the ci
# preset), the configure fails. The subdirectories test the <package>_FOUND variables
# set here.
#
#   GTest          the GoogleTest suites of tests/ (and tests/scenarios, tests/box2d)
#   orocos_kdl     tests/kinematics/kdl_agreement_test.cpp; benchmarks/
#   benchmark      benchmarks/
#   nlohmann_json  examples/common, examples/scenario, examples/box2d, the scenario-file
#                  tests, tests/box2d, the benchmark report tool
#   CLI11          examples/scenario, examples/campaign, examples/box2d (and the tests
#                  that run them)
#   box2d          examples/box2d, tests/box2d
#   mujoco         examples/mujoco, tests/mujoco (Debian's libmujoco-dev 2.2.2; its config
#                  also needs OpenGL and the qhull headers, see scripts/lib/packages.sh)
#   urdfdom        the URDF reader inhand::urdf (include/inhand/urdf.hpp) and tests/urdf;
#                  looked for always, as it is part of the installed package (component
#                  `urdf`); Debian's liburdfdom-dev 3.0
#   kdl_parser     tests/urdf (KDL reading the same URDF files as the reference);
#                  Debian's libkdl-parser-dev 1.14, found by header and library (below)

# inhand_report_missing(<package> <what needs it>): fails the configure (with
# INHAND_REQUIRE_ALL_DEPENDENCIES) or says what is skipped when <package>_FOUND is false.
macro(inhand_report_missing package what)
  if(NOT ${package}_FOUND)
    if(INHAND_REQUIRE_ALL_DEPENDENCIES)
      message(FATAL_ERROR "inhand: package ${package} not found; ${what} need it "
                          "(INHAND_REQUIRE_ALL_DEPENDENCIES is ON)")
    endif()
    message(STATUS "inhand: package ${package} not found: ${what} skipped")
  endif()
endmacro()

# inhand_find_optional_package(<package> <what needs it> [find_package arguments...])
macro(inhand_find_optional_package package what)
  find_package(${package} ${ARGN} QUIET)
  inhand_report_missing(${package} "${what}")
endmacro()

# kdl_parser is found by its header and library, not by find_package(kdl_parser): its
# catkin config (Debian's libkdl-parser-dev) loads ROS's urdf, pluginlib and
# ament_cmake_core, which runs Python (ament_package) at configure time and stops the
# configure with an error (not silenced by QUIET) where the first python3 on PATH lacks
# that module. The library itself needs only orocos_kdl, urdfdom and tinyxml, whose
# shared libraries it names itself. Sets kdl_parser_FOUND, _INCLUDE_DIRS, _LIBRARIES.
macro(inhand_find_kdl_parser what)
  find_path(INHAND_KDL_PARSER_INCLUDE_DIR kdl_parser/kdl_parser.hpp)
  find_library(INHAND_KDL_PARSER_LIBRARY kdl_parser)
  set(kdl_parser_FOUND FALSE)
  if(INHAND_KDL_PARSER_INCLUDE_DIR AND INHAND_KDL_PARSER_LIBRARY AND orocos_kdl_FOUND)
    set(kdl_parser_FOUND TRUE)
    set(kdl_parser_INCLUDE_DIRS ${INHAND_KDL_PARSER_INCLUDE_DIR} ${orocos_kdl_INCLUDE_DIRS})
    set(kdl_parser_LIBRARIES ${INHAND_KDL_PARSER_LIBRARY} ${orocos_kdl_LIBRARIES})
  endif()
  inhand_report_missing(kdl_parser "${what}")
endmacro()

inhand_find_optional_package(urdfdom "the URDF reader (inhand::urdf) and its tests" CONFIG)
if(INHAND_BUILD_TESTS)
  inhand_find_optional_package(GTest "the GoogleTest suites (tests/)")
endif()
if(INHAND_BUILD_TESTS OR INHAND_BUILD_BENCHMARKS)
  inhand_find_optional_package(orocos_kdl "the KDL agreement test and the benchmarks")
endif()
if(INHAND_BUILD_TESTS)
  inhand_find_kdl_parser("the URDF reader's tests (tests/urdf)")
endif()
if(INHAND_BUILD_BENCHMARKS)
  inhand_find_optional_package(benchmark "the benchmarks (benchmarks/)")
endif()
if(INHAND_BUILD_TESTS OR INHAND_BUILD_BENCHMARKS OR INHAND_BUILD_EXAMPLES)
  inhand_find_optional_package(nlohmann_json
    "the scenario runner, the Box2D demo, their tests and the benchmark report" 3)
endif()
if(INHAND_BUILD_EXAMPLES)
  inhand_find_optional_package(CLI11 "the scenario runner, the campaign and the Box2D demo"
    CONFIG)
endif()
if(INHAND_BUILD_TESTS OR INHAND_BUILD_EXAMPLES)
  inhand_find_optional_package(box2d "the Box2D demo and its tests" CONFIG)
  inhand_find_optional_package(mujoco "the MuJoCo hands (examples/mujoco) and their tests"
    CONFIG)
endif()

# What the example programs that tests run will be built.
set(INHAND_HAVE_SCENARIO_RUNNER OFF)
set(INHAND_HAVE_CAMPAIGN OFF)
set(INHAND_HAVE_BOX2D_DEMO OFF)
if(INHAND_BUILD_EXAMPLES AND CLI11_FOUND)
  set(INHAND_HAVE_CAMPAIGN ON)
  if(nlohmann_json_FOUND)
    set(INHAND_HAVE_SCENARIO_RUNNER ON)
    if(box2d_FOUND)
      set(INHAND_HAVE_BOX2D_DEMO ON)
    endif()
  endif()
endif()
