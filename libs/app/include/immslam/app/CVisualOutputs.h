/* imm-monoslam — the visual outputs of a run: overlay images, MRPT scenes (.3Dscene) and their
 * PNG snapshots, plots (model probabilities as the IMM paper's Fig. 4, search areas, ATE). */
#pragma once

#include <immslam/app/CLiveView.h>
#include <immslam/app/app_options.h>
#include <immslam/eval/ate.h>
#include <immslam/tracking/CMonoSlamIMM.h>
#include <immslam/system/CMonoSlamSystem.h>
#include <immslam/viz/COverlayWriter.h>
#include <immslam/viz/scene.h>

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace immslam::app
{
class CVisualOutputs
{
 public:
  /** \param liveWindows also show the overlay and the scene in live MRPT windows (CLiveView). */
  CVisualOutputs(const std::string& outDir, const TOutputOptions& opts, const slam::CMonoSlamIMM& slam,
                 bool liveWindows = false);
  ~CVisualOutputs();

  /** Per processed frame: overlay (when enabled), periodic scene, and the series for the plots. */
  void onFrame(std::size_t frameIndex, const cv::Mat& image, const system::TSystemFrame& fr,
               const slam::CMonoSlamIMM& slam, const core::TTrajectory& trajectory,
               const std::vector<std::string>& extraText = {});

  /** At the end: scene.3Dscene (+ scene.png), plots. \param labels true motion label per processed
   * frame (empty if unknown). Never throws for a figure that cannot be made (logs a warning). */
  void finish(const slam::CMonoSlamIMM& slam, const core::TTrajectory& trajectory,
              const std::optional<core::TTrajectory>& groundTruth, const std::optional<eval::TAteResult>& ate,
              const std::vector<std::string>& labels, std::vector<std::string>& warnings);

  /** Scene content of the current state (trajectory, camera, map with uncertainties). */
  viz::TSceneContent sceneContent(const slam::CMonoSlamIMM& slam, const core::TTrajectory& trajectory,
                                  const std::string& title) const;

 private:
  std::string m_dir;
  TOutputOptions m_opts;
  std::unique_ptr<viz::COverlayWriter> m_overlays;
  std::unique_ptr<CLiveView> m_live;
  // Series of the end-of-run plots, kept only when plots are on (a few bytes per frame: a long live run
  // without plots keeps no per-frame series here).
  std::vector<double> m_times, m_areas;
  std::vector<double> m_probs;  ///< model probabilities, one row of r per frame (row-major)
  std::vector<std::string> m_modelNames;
  std::map<std::int64_t, std::vector<Vec3>> m_tracks;  ///< dynamic tracks (world positions) by id
};
}  // namespace immslam::app
