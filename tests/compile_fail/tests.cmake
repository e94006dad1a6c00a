# Compile-failure checks: impossible ReactiveController template arguments are refused
# by a static_assert with a one-line message. Each case compiles
# bad_template_arguments.cpp with -fsyntax-only and passes when the compiler prints the
# expected message (a compile that fails for another reason does not match).
set(_inhand_cf_src ${CMAKE_CURRENT_SOURCE_DIR}/compile_fail/bad_template_arguments.cpp)
set(_inhand_cf_cases
    "1|NumFingers must be >= 1"
    "2|NumFingers must be >= 1"
    "3|Dim must be 2 \\(planar\\) or 3"
    "4|Dof must be >= 1"
    "5|with a fixed Dof, MaxDof must equal Dof"
    "6|Scalar must be float, double or long double"
    "7|MaxDof must be >= 1")
foreach(_case IN LISTS _inhand_cf_cases)
  string(REPLACE "|" ";" _parts "${_case}")
  list(GET _parts 0 _n)
  list(GET _parts 1 _msg)
  add_test(
    NAME compile_fail.reactive_controller_${_n}
    COMMAND ${CMAKE_CXX_COMPILER} -std=c++17 -fsyntax-only -DINHAND_CASE=${_n}
            "-I$<JOIN:$<TARGET_PROPERTY:inhand,INTERFACE_INCLUDE_DIRECTORIES>,;-I>"
            "-I$<JOIN:$<TARGET_PROPERTY:Eigen3::Eigen,INTERFACE_INCLUDE_DIRECTORIES>,;-I>"
            ${_inhand_cf_src}
    COMMAND_EXPAND_LISTS)
  set_tests_properties(compile_fail.reactive_controller_${_n}
                       PROPERTIES PASS_REGULAR_EXPRESSION "ReactiveController: ${_msg}" LABELS compile_fail)
endforeach()
