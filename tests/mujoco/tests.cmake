# The MuJoCo hands (examples/mujoco, models/): GoogleTest cases that link MuJoCo, so they
# are built here rather than by the *_test.cpp glob of tests/CMakeLists.txt (which links
# only inhand and GoogleTest); the file names avoid that glob. Skipped without MuJoCo or
# GoogleTest (cmake/inhandOptionalPackages.cmake says which is missing). Label mujoco.
#   mujoco_chains      the chains read from the compiled models (three-finger and
#                      Shadow-like hands, cylinder and box scenes) against MuJoCo's own
#                      kinematics (fingertip positions and Jacobians, random configurations)
#                      and the presets; the open hand clear of the object
#   mujoco_box         the paper's slender box on the MJCF three-finger hand over its mass
#                      and the contacts' friction: the hold after release settles within
#                      the paper files' 1 s
#   mujoco_cylinder    the paper's cylinder translation in closed loop on the MJCF hand
#                      (the case with the paper's bounds is disabled: the grasp does not
#                      complete on MuJoCo yet; the file gives the figures)
#   mujoco_scenario_file  the scenario file's MuJoCo settings (plant.engine "mujoco") have
#                      the adapter's defaults; only with the scenario-file parser
#                      (nlohmann-json). The files themselves run as scenario.mujoco.* tests
#                      (tests/scenarios/tests.cmake)
#   mujoco_urdf        MuJoCo's URDF import of models/urdf/*.urdf against inhand::urdf
#                      reading the same files (fingertip positions, random configurations);
#                      only where inhand::urdf exists (urdfdom found)
if(mujoco_FOUND AND GTest_FOUND)
  set(names mujoco_box mujoco_chains mujoco_cylinder)
  if(TARGET inhand::urdf)
    list(APPEND names mujoco_urdf)
  endif()
  foreach(name IN LISTS names)
    add_executable(${name} ${CMAKE_CURRENT_LIST_DIR}/${name}.cpp)
    target_include_directories(${name} PRIVATE
      ${CMAKE_CURRENT_SOURCE_DIR} ${PROJECT_SOURCE_DIR}/examples/mujoco)
    target_compile_definitions(${name} PRIVATE INHAND_MODELS_DIR="${PROJECT_SOURCE_DIR}/models"
      INHAND_TEST_DATA_DIR="${CMAKE_CURRENT_LIST_DIR}/data")
    target_link_libraries(${name} PRIVATE inhand::sim inhand_test_instances inhand_warnings mujoco::mujoco
                          GTest::gtest GTest::gtest_main)
    inhand_add_gtest(${name} PREFIX mujoco. LABELS mujoco TIMEOUT 120)
  endforeach()
  if(TARGET inhand::urdf)
    target_link_libraries(mujoco_urdf PRIVATE inhand::urdf)
  endif()
  if(nlohmann_json_FOUND)
    add_executable(mujoco_scenario_file ${CMAKE_CURRENT_LIST_DIR}/mujoco_scenario_file.cpp)
    target_include_directories(mujoco_scenario_file PRIVATE ${PROJECT_SOURCE_DIR}/examples
      ${PROJECT_SOURCE_DIR}/examples/scenario ${PROJECT_SOURCE_DIR}/examples/mujoco)
    target_compile_definitions(mujoco_scenario_file PRIVATE
      INHAND_MODELS_DIR="${PROJECT_SOURCE_DIR}/models")
    target_link_libraries(mujoco_scenario_file PRIVATE inhand::sim mujoco::mujoco
      nlohmann_json::nlohmann_json inhand_warnings GTest::gtest GTest::gtest_main)
    inhand_add_gtest(mujoco_scenario_file PREFIX mujoco. LABELS mujoco TIMEOUT 60)
  endif()
endif()
