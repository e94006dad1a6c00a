# The packages the tests, benchmarks and examples use (the library itself needs only
# Eigen). Each is looked for once, here, when a part that uses it is enabled; where one
# is missing the parts that need it are skipped with a message naming the package, or,
# with INHAND_REQUIRE_ALL_DEPENDENCIES=ON (scripts/test, the ci preset), the configure
# fails. The subdirectories test the <package>_FOUND variables set here.
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

# inhand_find_optional_package(<package> <what needs it> [find_package arguments...])
macro(inhand_find_optional_package package what)
  find_package(${package} ${ARGN} QUIET)
  if(NOT ${package}_FOUND)
    if(INHAND_REQUIRE_ALL_DEPENDENCIES)
      message(FATAL_ERROR "inhand: package ${package} not found; ${what} need it "
                          "(INHAND_REQUIRE_ALL_DEPENDENCIES is ON)")
    endif()
    message(STATUS "inhand: package ${package} not found: ${what} skipped")
  endif()
endmacro()

if(INHAND_BUILD_TESTS)
  inhand_find_optional_package(GTest "the GoogleTest suites (tests/)")
endif()
if(INHAND_BUILD_TESTS OR INHAND_BUILD_BENCHMARKS)
  inhand_find_optional_package(orocos_kdl "the KDL agreement test and the benchmarks")
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
