# CMake generated Testfile for 
# Source directory: /work/main/libs
# Build directory: /work/main/build/libs
# 
# This file includes the relevant testing commands required for 
# testing this directory and lists subdirectories to be tested as well.
subdirs("math")
