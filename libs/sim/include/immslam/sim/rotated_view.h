/* imm-monoslam — a rotating camera made from a real video (imm-rotate).
 *
 * The shadow filter's claims (MonoSLAMBOT, Fig. 4 and the "hand in front of the camera" runs) need
 * real video of a hand or a person moving in front of a moving camera, with the truth of which
 * pixels move and of the camera's motion. Videos of real hands are easy to find, but mostly from a
 * camera that stood still (a tripod, a webcam). A pure rotation of a central camera changes its image
 * by a homography that needs no depth: a virtual camera with the same optical centre, rotated by
 * R(t), sees at its pixel u' what the real camera saw at `project(R(t) unproject'(u'))`. So
 * rotateStillVideo() turns such a video into the video a rotating camera would have taken, exactly
 * up to the resampling (bilinear) and the real lens model given in the calibration; the virtual image
 * is a crop of the real one (smaller, same focal length) so that it stays inside the real view.
 *
 * Truth written with it: groundtruth.txt (the rotation, no translation; composed with the source's own
 * ground truth when it has one), and for a camera that stood still (`still`) motion_labels.txt and
 * masks/ in the renderer's format (0 static world, 1 moving): the foreground of OpenCV's Gaussian-mixture
 * background subtractor (`cv::BackgroundSubtractorMOG2`), learned over the whole video first and then
 * applied to each frame without learning, opened, small holes filled, dilated, warped with the frame.
 * Shadows that MOG2 recognises (a darker copy of the background) count as background; reflections and
 * shadows it does not recognise are marked. */
#pragma once

#include <immslam/math/types.h>

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::sim
{
/** Options of rotateStillVideo(). Angles in degrees, time in frames. */
struct TRotatedViewOptions
{
  std::string calibFile;  ///< calib.txt of the source (required for videos; overrides a folder's own)
  int width = 0;          ///< virtual image width (0 = 0.8 x the source's, even)
  int height = 0;         ///< virtual image height (0 = 0.8 x the source's, even)
  double focal = 0;       ///< virtual focal length in pixels (0 = the source's fx)
  /** Amplitudes of the three rotations (camera frame: pan about y, tilt about x, roll about z); each
   * angle is A sin(2 pi i / P_k) with periods P, 1.37 P and 1.83 P (never in phase): R(0) = I. */
  double panDeg = 3.0, tiltDeg = 2.0, rollDeg = 1.5;
  double periodFrames = 120;  ///< P
  /** The source camera stood still: write masks/ from the background (and treat the source
   * pose as the identity when the source has no ground truth of its own). */
  bool still = true;
  /** Squared Mahalanobis distance to every background mode above which a pixel is foreground
   * (`cv::BackgroundSubtractorMOG2`'s varThreshold; 16 = 4 sigma, OpenCV's default). */
  double varThreshold = 16;
  int dilatePx = 4;               ///< mask dilation radius, px (after a 3x3 opening)
  std::size_t maxFrames = 0;      ///< 0 = all
  double fps = 0;                 ///< frame rate of a video source (0 = the container's, else 30)
};

/** What rotateStillVideo() wrote. */
struct TRotatedViewStats
{
  std::size_t frames = 0;          ///< frames written
  std::size_t skipped = 0;         ///< source entries skipped (unreadable), not written
  double maxOutsideFraction = 0;   ///< largest fraction of a virtual image outside the real one (black)
  double meanMovingFraction = 0;   ///< mean fraction of the virtual image marked moving (still sources)
  double maxAngleDeg = 0;          ///< largest rotation angle from the first frame
};

/** The virtual camera's orientation in the source camera's frame at frame i (R(0) = I), as a
 * quaternion [qw qx qy qz]; see TRotatedViewOptions for the script. */
Vec4 rotatedViewQuaternion(const TRotatedViewOptions& o, std::size_t i);

/** Reads `source` (a dataset folder, a .rawlog or a video file OpenCV decodes) and writes
 * `outFolder` (CDatasetWriter layout): rgb/ (colour when the source is), rgb.txt with the source
 * timestamps, calib.txt (pinhole, the virtual camera), groundtruth.txt (still sources, and sources with
 * their own ground truth) and, for a still source, motion_labels.txt, masks/NNNNNN.png and background.png.
 * \throws std::invalid_argument for bad options, std::runtime_error naming the file for an unreadable
 *         source or calibration, a source without calibration, a virtual image larger than the
 *         source's, or an output that cannot be written. */
TRotatedViewStats rotateStillVideo(const std::string& source, const std::string& outFolder,
                                   const TRotatedViewOptions& options);

/** `imm-rotate SOURCE OUT_FOLDER [options]`.
 * \return 0 on success, 1 on bad input or failure (the message names the file), 2 on bad usage. */
int runRotateApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/** The usage text. */
std::string rotateAppUsage();
}  // namespace immslam::sim
