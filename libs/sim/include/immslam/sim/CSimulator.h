/* imm-monoslam — a scenario ready to render: ground truth, labels, masks, images, dataset output. */
#pragma once

#include <immslam/core/TTrajectory.h>
#include <immslam/sim/CCameraTrajectory.h>
#include <immslam/sim/CRenderer.h>
#include <immslam/sim/CWorld.h>
#include <immslam/sim/TScenario.h>

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace immslam::sim
{
/** One rendered frame with its ground truth. */
struct TSyntheticFrame
{
  std::size_t index = 0;
  double timestamp = 0;
  /** CV_8UC1 grey image (the luminance of `colour` when the scenario renders colour). */
  cv::Mat grey;
  /** CV_8UC3 BGR image, or empty. */
  cv::Mat colour;
  /** CV_8UC1 object mask: 0 static world, k moving object k. */
  cv::Mat mask;
  /** T_W_C of the camera. */
  core::TStampedPose T_W_C;
  EMotionLabel label = EMotionLabel::Stationary;
  /** T_W_O of every rendered moving object. */
  std::vector<TObjectPose> objects;
};

/** Timings of CSimulator::writeDataset(). */
struct TWriteStats
{
  std::size_t frames = 0;
  double renderSeconds = 0;  ///< ray casting, texturing, noise
  double totalSeconds = 0;   ///< including PNG encoding and files
};

/** Options of CSimulator::writePointTracks(). */
struct TPointTrackOptions
{
  int staticPoints = 200;     ///< points on the static world (room and static boxes)
  int pointsPerObject = 12;   ///< points on each moving object
  double noisePx = 0.5;       ///< standard deviation of the Gaussian noise of each projection (px)
};

/** The renderer of a scenario: builds the world and the camera path (checking that the camera
 * keeps `min_clearance` from walls, static boxes and moving objects), then renders any frame on
 * demand, deterministically (frame k depends only on the scenario and k). */
class CSimulator
{
 public:
  /** \throws std::runtime_error (naming the scenario) if the camera path is not in free space. */
  explicit CSimulator(TScenario scenario);

  const TScenario& scenario() const { return m_sc; }
  const CWorld& world() const { return m_world; }
  const CCameraTrajectory& cameraTrajectory() const { return m_traj; }
  const CRenderer& renderer() const { return m_renderer; }
  const camera::CCameraModel::Ptr& camera() const { return m_sc.camera; }

  /** Number of frames of the script. */
  std::size_t frameCount() const { return m_traj.size(); }

  /** Timestamp of frame k (s): start_time_s + k / fps. */
  double timestamp(std::size_t k) const { return m_sc.start_time_s + m_traj.time(k); }

  /** T_W_C of frame k. */
  core::TStampedPose cameraPose(std::size_t k) const;

  /** Camera ground truth of the first n frames (0: all). */
  core::TTrajectory groundTruth(std::size_t n = 0) const;

  /** The true motion over (t_{k-1}, t_k]. */
  EMotionLabel motionLabel(std::size_t k) const { return m_traj.label(k); }

  /** T_W_O of every rendered moving object at frame k. */
  std::vector<TObjectPose> objectPoses(std::size_t k) const;

  /** Renders frame k (image, mask and ground truth). */
  TSyntheticFrame render(std::size_t k) const;

  /** Only the object mask of frame k (much faster than render()). */
  cv::Mat renderMask(std::size_t k) const;

  /** Depth image of frame k (z in the camera frame, CV_32F). */
  cv::Mat renderDepth(std::size_t k) const;

  /** What the ray of pixel uv hits at frame k (camera at its ground-truth pose). */
  std::optional<TRayHit> raycast(std::size_t k, const Vec2& uv) const;

  /** What the ray of pixel uv hits with the camera at T_W_C and the objects at `timestamp`. */
  std::optional<TRayHit> raycast(const core::TStampedPose& T_W_C, const Vec2& uv, double timestamp) const;

  /** Writes the first n frames (0: all) as a dataset folder: rgb/, rgb.txt, calib.txt,
   * groundtruth.txt (T_W_C) through io::CDatasetWriter, plus motion_labels.txt, camera_velocity.txt,
   * objects_groundtruth.txt, masks/NNNNNN.png, world_boxes.txt and scenario.ini (the effective
   * scenario), each text file with '#' header comments.
   * \param progress called after each frame with the number of frames written. */
  /** Writes point tracks with ground truth, for measurement-level experiments with known data
   * association (the MonoSLAMBOT paper's Fig. 5: "data association was performed manually"): points
   * on the textured surfaces, sampled where random rays of random frames hit them (static world, and
   * each moving object in its own frame, moving with it), and for each of the first n frames (0: all)
   * every point in view and not occluded (the ray through its projection hits it first), its
   * projection plus Gaussian noise. Lines `timestamp point_id kind x y z u v`, kind `static` or
   * `moving`, (x, y, z) the true world position then: the format of monoslammot_synth19's
   * points_groundtruth.txt ([input] known_association, slam-eval classification --points, slam-eval
   * tracks). Deterministic for a scenario (its seed). Returns the number of lines written.
   * \throws std::runtime_error naming the file if it cannot be written. */
  std::size_t writePointTracks(const std::string& path, std::size_t n = 0, const TPointTrackOptions& opts = {}) const;

  TWriteStats writeDataset(const std::string& folder, std::size_t n = 0,
                           const std::function<void(std::size_t)>& progress = {}) const;

 private:
  double motionTime(std::size_t k) const { return m_traj.time(k); }
  void checkClearance() const;

  TScenario m_sc;
  CWorld m_world;
  CCameraTrajectory m_traj;
  CRenderer m_renderer;
};
}  // namespace immslam::sim
