# Empty dependencies file for math_unittest.
# This may be replaced when dependencies are built.
