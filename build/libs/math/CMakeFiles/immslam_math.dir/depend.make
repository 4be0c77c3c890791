# Empty dependencies file for immslam_math.
# This may be replaced when dependencies are built.
