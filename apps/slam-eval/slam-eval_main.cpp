/* slam-eval: evaluation of imm-monoslam's outputs against ground truth (ATE/RPE, motion
 * segmentation, static/dynamic classification, NIS); see --help. */
#include <immslam/eval/slam_eval_app.h>

#include <iostream>

int main(int argc, char** argv)
{
  return immslam::eval::runSlamEvalApp(std::vector<std::string>(argv, argv + argc), std::cout, std::cerr);
}
