/* imm-render: renders a synthetic image sequence with ground truth (see immslam/sim/render_app.h). */
#include <immslam/sim/render_app.h>

#include <iostream>

int main(int argc, char** argv)
{
  return immslam::sim::runRenderApp(std::vector<std::string>(argv + 1, argv + argc), std::cout, std::cerr);
}
