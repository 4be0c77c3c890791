/* imm-monoslam — camera parameter sets shared by the camera tests: the calibrations of
 * ../shared/data/<set>/calib.txt, hard-coded so the tests run without the data. */
#pragma once

#include <immslam/camera/CDavisonCamera.h>
#include <immslam/camera/CFisheyeCamera.h>
#include <immslam/camera/COpenCVCamera.h>
#include <immslam/camera/CPinholeCamera.h>

#include <memory>
#include <string>
#include <vector>

namespace immslam::camera::test
{
/** A named camera for parametrised tests. */
struct TTestCamera
{
  std::string name;
  CCameraModel::Ptr cam;
};

inline std::shared_ptr<const COpenCVCamera> eurocCamera()
{
  return std::make_shared<COpenCVCamera>(752, 480, 458.654, 457.296, 367.215, 248.375, -0.28340811,
      0.07395907, 0.00019359, 1.76187114e-05, 0);
}

/** Strong barrel distortion with tangential terms and a fold at r ~ 2.28 (66 degrees); the image
 * corners reach 61 degrees. */
inline std::shared_ptr<const COpenCVCamera> strongOpenCVCamera()
{
  return std::make_shared<COpenCVCamera>(640, 480, 300, 300, 320, 240, -0.3, 0.1, 0.002, -0.0015, -0.01);
}

inline std::shared_ptr<const CDavisonCamera> monoslamCamera()
{
  return std::make_shared<CDavisonCamera>(320, 240, 195, 195, 162, 125, 9e-06);
}

/** The TUM visual-inertial data set's cam0 (512x512 Kannala-Brandt, published calibration): its
 * image corners lie beyond 90 degrees from the axis (outside the lens's image circle). */
inline std::shared_ptr<const CFisheyeCamera> tumviCamera()
{
  return std::make_shared<CFisheyeCamera>(512, 512, 190.97847715128717, 190.9733070521226, 254.93170605935475,
      256.8974428996504, 0.0034823894022493434, 0.0007150348452162257, -0.0020532361418706202,
      0.00020293673591811182);
}

inline std::vector<TTestCamera> testCameras()
{
  return {
      {"visp_rbt_pinhole", std::make_shared<CPinholeCamera>(640, 480, 607.178466796875,
                               607.2342529296875, 321.39129638671875, 241.91822814941406)},
      {"synth19_pinhole", std::make_shared<CPinholeCamera>(320, 240, 170, 170, 160, 120)},
      {"euroc_opencv", eurocCamera()},
      {"strong_opencv", strongOpenCVCamera()},
      {"monoslam_davison", monoslamCamera()},
      {"pincushion_davison", std::make_shared<CDavisonCamera>(320, 240, 195, 190, 158, 121, -3e-06)},
      // A 150-degree lens on a 640x480 sensor (corners at 77 degrees) and the TUM-VI lens on the
      // central 320x320 of its sensor (corners at 68 degrees).
      {"wide_fisheye", std::make_shared<CFisheyeCamera>(640, 480, 300, 301, 319.5, 239.5, -0.012, 0.0051, -0.0013,
                           0.00015)},
      {"tumvi_fisheye_crop", std::make_shared<CFisheyeCamera>(320, 320, 190.97847715128717, 190.9733070521226,
                                 158.93170605935475, 160.8974428996504, 0.0034823894022493434,
                                 0.0007150348452162257, -0.0020532361418706202, 0.00020293673591811182)},
  };
}
}  // namespace immslam::camera::test
