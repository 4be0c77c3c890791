file(REMOVE_RECURSE
  "../../lib/libimmslam-math.a"
  "../../lib/libimmslam-math.pdb"
  "CMakeFiles/immslam_math.dir/src/bearing.cpp.o"
  "CMakeFiles/immslam_math.dir/src/bearing.cpp.o.d"
  "CMakeFiles/immslam_math.dir/src/chi2.cpp.o"
  "CMakeFiles/immslam_math.dir/src/chi2.cpp.o.d"
  "CMakeFiles/immslam_math.dir/src/gaussian.cpp.o"
  "CMakeFiles/immslam_math.dir/src/gaussian.cpp.o.d"
  "CMakeFiles/immslam_math.dir/src/quaternion.cpp.o"
  "CMakeFiles/immslam_math.dir/src/quaternion.cpp.o.d"
)

# Per-language clean rules from dependency scanning.
foreach(lang CXX)
  include(CMakeFiles/immslam_math.dir/cmake_clean_${lang}.cmake OPTIONAL)
endforeach()
