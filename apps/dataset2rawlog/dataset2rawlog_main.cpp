/* dataset2rawlog FOLDER OUT.rawlog [--embed] [--layout obs|sf]: dataset folder -> MRPT rawlog. */
#include <immslam/io/dataset2rawlog.h>

#include <iostream>
#include <string>
#include <vector>

int main(int argc, char** argv)
{
  return immslam::io::dataset2rawlogCli(std::vector<std::string>(argv + 1, argv + argc), std::cout, std::cerr);
}
