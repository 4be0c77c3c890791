file(REMOVE_RECURSE
  "../../tests/math_unittest"
  "../../tests/math_unittest.pdb"
  "CMakeFiles/math_unittest.dir/tests/math_unittest.cpp.o"
  "CMakeFiles/math_unittest.dir/tests/math_unittest.cpp.o.d"
  "math_unittest[1]_tests.cmake"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/math_unittest.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
