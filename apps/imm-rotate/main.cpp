/* imm-rotate: a rotating camera's video made from a still camera's real video, with the rotation and
 * the moving pixels as truth (see immslam/sim/rotated_view.h). */
#include <immslam/sim/rotated_view.h>

#include <iostream>

int main(int argc, char** argv)
{
  return immslam::sim::runRotateApp(std::vector<std::string>(argv + 1, argv + argc), std::cout, std::cerr);
}
