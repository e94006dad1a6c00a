# The planar Box2D demo (examples/box2d): closed-loop scenarios with the library's
# ReactiveController<double, 2, 2, 3> on a Box2D hand. Needs libbox2d-dev and
# nlohmann-json3-dev; skipped with a message otherwise. (The file name avoids the
# *_test.cpp glob of tests/CMakeLists.txt, which would build it without Box2D.)
#   box2d.*                          GoogleTest cases (label box2d)
#   box2d.trace_identical_across_runs  the demo program run twice: identical trace files
# box2d, nlohmann_json, GTest and CLI11: cmake/inhandOptionalPackages.cmake.
if(box2d_FOUND AND nlohmann_json_FOUND AND GTest_FOUND)
  add_executable(box2d_planar_scenarios ${CMAKE_CURRENT_LIST_DIR}/planar_scenarios.cpp)
  target_include_directories(box2d_planar_scenarios PRIVATE
    ${CMAKE_CURRENT_SOURCE_DIR} ${PROJECT_SOURCE_DIR}/examples ${PROJECT_SOURCE_DIR}/examples/box2d)
  target_link_libraries(box2d_planar_scenarios PRIVATE inhand::sim inhand_test_instances inhand_warnings box2d::box2d
                        nlohmann_json::nlohmann_json GTest::gtest GTest::gtest_main)
  inhand_add_gtest(box2d_planar_scenarios PREFIX box2d. LABELS box2d TIMEOUT 120)

  # Bit-for-bit determinism of the program's output: two runs, byte-identical traces.
  # (Examples are added after the tests, so the target cannot be tested for here; the
  # program also needs CLI11.)
  if(INHAND_HAVE_BOX2D_DEMO)
    add_test(NAME box2d.trace_identical_across_runs
      COMMAND ${CMAKE_COMMAND} -DPROGRAM=$<TARGET_FILE:box2d_planar>
              -DWORK_DIR=${CMAKE_CURRENT_BINARY_DIR}/box2d_determinism
              -P ${CMAKE_CURRENT_LIST_DIR}/run_twice.cmake)
    set_tests_properties(box2d.trace_identical_across_runs PROPERTIES LABELS "box2d;example" TIMEOUT 120)
  endif()
endif()
