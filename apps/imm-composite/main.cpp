/* imm-composite: pastes moving objects into a real image sequence, with masks as truth (see
 * immslam/sim/composite.h). */
#include <immslam/sim/composite.h>

#include <iostream>

int main(int argc, char** argv)
{
  return immslam::sim::runCompositeApp(std::vector<std::string>(argv + 1, argv + argc), std::cout, std::cerr);
}
