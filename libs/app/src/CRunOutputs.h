/* imm-monoslam — private to libs/app: the outputs of a run, fed frame by frame (files, pictures,
 * plot labels, the matches for the final bundle adjustment, the frame statistics) and finished at the
 * end (map, ATE, refined trajectory, scene, plots). */
#pragma once

#include <immslam/app/CImmMonoSlamApp.h>
#include <immslam/app/COutputFiles.h>
#include <immslam/app/CVisualOutputs.h>
#include <immslam/eval/search_nis.h>
#include <immslam/system/CMonoSlamSystem.h>

#include "CTrajectorySmoothing.h"
#include "run_inputs.h"

#include <map>
#include <memory>
#include <string>
#include <vector>

namespace immslam::sim
{
class CSyntheticSource;
}

namespace immslam::app::detail
{
/** The output folder of a run and what its end needs from the frames (COutputFiles, CVisualOutputs,
 * the true motion labels, [output] refine_trajectory's matches, frame times and match counts). */
class CRunOutputs
{
 public:
  /** Creates the output folder and its per-frame files for the system `sys` (its model names and
   * whether the shadow filter is on). \throws std::runtime_error naming a path that cannot be created. */
  CRunOutputs(const TRunContext& ctx, const TRunInputs& in, const system::CMonoSlamSystem& sys);

  /** The per-frame files (trajectory.txt, ...). */
  const COutputFiles& files() const { return m_files; }

  /** One processed frame: the files, the pictures, its true motion label (for the plots), its inlier
   * matches ([output] refine_trajectory), the smoother ([output] smooth_trajectory), its time and
   * match count.
   * \param processed the number of frames processed before this one. */
  void addFrame(std::size_t processed, const io::TFrame& frame, const system::TSystemFrame& fr,
                const slam::CMonoSlamIMM& slam);

  /** At the end: warnings for frames without mask or tracks, map.csv, the frame statistics and the
   * ATE of `summary`, trajectory_refined.txt (with the inputs' final camera), trajectory_smoothed.txt,
   * scene and plots
   * (warnings logged). */
  void finish(const slam::CMonoSlamIMM& slam, TRunSummary& summary);

 private:
  /** The true motion label of a frame, when the input knows it. */
  void addLabel(const io::TFrame& frame);
  /** The low-innovation and rescued inliers of a frame, for the final bundle adjustment. */
  void addRefineRows(const system::TSystemFrame& fr);

  const TRunContext& m_ctx;
  const TRunInputs& m_in;
  COutputFiles m_files;
  CVisualOutputs m_visuals;
  const sim::CSyntheticSource* m_synthetic;               ///< the source, when it is the renderer
  std::map<long long, std::string> m_folderLabels;        ///< motion_labels.txt of a dataset folder
  std::vector<std::string> m_labels;                      ///< true label per processed frame (plots)
  std::vector<eval::TSearchRow> m_refineRows;             ///< matches used in the updates
  std::unique_ptr<CTrajectorySmoothing> m_smoothing;      ///< [output] smooth_trajectory (made at the first frame)
  std::vector<double> m_frameMs, m_matched;               ///< per processed frame
};
}  // namespace immslam::app::detail
