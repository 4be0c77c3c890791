// Builds the full system from an in-memory config against the installed package and runs 3 frames.
#include <immslam/camera/CCameraModel.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <opencv2/core.hpp>

#include <iostream>

int main()
{
  mrpt::config::CConfigFileMemory cfg("[system]\nshadow_filter = true\n");
  auto cam = immslam::camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  immslam::system::CMonoSlamSystem sys(cfg, cam);
  cv::Mat img(240, 320, CV_8UC1);
  cv::randu(img, 0, 255);
  for (int k = 0; k < 3; ++k) sys.processFrame(k / 30.0, img);
  std::cout << "models " << sys.slam().models().size() << " map " << sys.slam().features().size() << "\n";
  return 0;
}
