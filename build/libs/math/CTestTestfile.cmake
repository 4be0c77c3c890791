# CMake generated Testfile for 
# Source directory: /work/main/libs/math
# Build directory: /work/main/build/libs/math
# 
# This file includes the relevant testing commands required for 
# testing this directory and lists subdirectories to be tested as well.
include("/work/main/build/libs/math/math_unittest[1]_include.cmake")
