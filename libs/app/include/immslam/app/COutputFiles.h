/* imm-monoslam — the output folder of a run (../shared/CONTRACT.md "Output folder"): files are
 * created at the start and written frame by frame (flushed), so an interrupted or failed run keeps
 * everything up to its last frame. */
#pragma once

#include <immslam/core/TTrajectory.h>
#include <immslam/io/CCsvWriter.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <fstream>
#include <memory>
#include <string>

namespace immslam::app
{
class COutputFiles
{
 public:
  /** Creates the folder and the per-frame files (existing files are overwritten).
   * \throws std::runtime_error naming the path that cannot be created. */
  /** \param shadow also classifications.csv and tracks.csv (shadow filter on).
   * \param relativePoses also relative_poses.csv ([output] relative_pose_lag). */
  COutputFiles(const std::string& dir, const slam::CMonoSlamIMM& slam, bool shadow, bool searchLog = false,
               bool relativePoses = false);

  /** Appends one processed frame to trajectory.txt, model_probabilities.csv and frame_stats.csv. */
  void addFrame(const system::TSystemFrame& fr, const slam::CMonoSlamIMM& slam);

  /** Writes map.csv (final map, world frame). */
  void writeMap(const slam::CMonoSlamIMM& slam) const;

  const core::TTrajectory& trajectory() const { return m_traj; }
  std::string path(const std::string& name) const;

 private:
  std::string m_dir;
  std::ofstream m_trajFile;
  std::unique_ptr<io::CCsvWriter> m_probs, m_stats, m_searches, m_classes, m_tracks, m_shadowLog, m_relative;
  core::TTrajectory m_traj;
};
}  // namespace immslam::app
