/* imm-eval: ATE of an estimated TUM trajectory against ground truth (see --help). */
#include <immslam/eval/eval_app.h>

#include <iostream>

int main(int argc, char** argv)
{
  return immslam::eval::runEvalApp(std::vector<std::string>(argv, argv + argc), std::cout, std::cerr);
}
