# structure.layout: the include graph points one way (math <- kinematics <- controller
# <- sim, urdf) and no public header exceeds 300 lines (check_layout.cmake).
add_test(NAME structure.layout
  COMMAND ${CMAKE_COMMAND} -DINCLUDE_DIR=${PROJECT_SOURCE_DIR}/include -DMAX_LINES=300
          -P ${CMAKE_CURRENT_LIST_DIR}/check_layout.cmake)
set_tests_properties(structure.layout PROPERTIES LABELS structure TIMEOUT 60)
