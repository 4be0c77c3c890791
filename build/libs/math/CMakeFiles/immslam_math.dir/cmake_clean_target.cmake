file(REMOVE_RECURSE
  "../../lib/libimmslam-math.a"
)
