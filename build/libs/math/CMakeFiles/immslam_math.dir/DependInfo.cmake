
# Consider dependencies only in project.
set(CMAKE_DEPENDS_IN_PROJECT_ONLY OFF)

# The set of languages for which implicit dependencies are needed:
set(CMAKE_DEPENDS_LANGUAGES
  )

# The set of dependency files which are needed:
set(CMAKE_DEPENDS_DEPENDENCY_FILES
  "/work/main/libs/math/src/bearing.cpp" "libs/math/CMakeFiles/immslam_math.dir/src/bearing.cpp.o" "gcc" "libs/math/CMakeFiles/immslam_math.dir/src/bearing.cpp.o.d"
  "/work/main/libs/math/src/chi2.cpp" "libs/math/CMakeFiles/immslam_math.dir/src/chi2.cpp.o" "gcc" "libs/math/CMakeFiles/immslam_math.dir/src/chi2.cpp.o.d"
  "/work/main/libs/math/src/gaussian.cpp" "libs/math/CMakeFiles/immslam_math.dir/src/gaussian.cpp.o" "gcc" "libs/math/CMakeFiles/immslam_math.dir/src/gaussian.cpp.o.d"
  "/work/main/libs/math/src/quaternion.cpp" "libs/math/CMakeFiles/immslam_math.dir/src/quaternion.cpp.o" "gcc" "libs/math/CMakeFiles/immslam_math.dir/src/quaternion.cpp.o.d"
  )

# Targets to which this target links.
set(CMAKE_TARGET_LINKED_INFO_FILES
  )

# Fortran module output directory.
set(CMAKE_Fortran_TARGET_MODULE_DIR "")
