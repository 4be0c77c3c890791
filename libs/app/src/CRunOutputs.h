/* imm-monoslam — private to libs/app: the writers of a run (output_sinks.h), chosen by [output] and
 * the command line and put in the order the frame loop tells them. */
#pragma once

#include <immslam/app/CImmMonoSlamApp.h>
#include <immslam/app/COutputFiles.h>
#include <immslam/system/CMonoSlamSystem.h>

#include "IFrameSink.h"
#include "run_inputs.h"

#include <memory>
#include <vector>

namespace immslam::app::detail
{
/** The output folder of a run and its writers: the progress line (on a terminal), the per-frame
 * files, the statistics of the summary, [output] refine_trajectory, overlays, live windows (with a
 * display, without --no-gui), scenes, and the truth series the figures need (motion_labels.csv, ate.csv). */
class CRunOutputs
{
 public:
  /** Creates the output folder and its per-frame files for the system `sys` (its model names and
   * whether the shadow filter is on), and calib_guessed.txt when `calibrationGuessed`.
   * \throws std::runtime_error naming a path that cannot be created. */
  CRunOutputs(const TRunContext& ctx, const TRunInputs& in, const system::CMonoSlamSystem& sys,
              const TRunSummary& summary, bool calibrationGuessed);
  ~CRunOutputs();

  /** The per-frame files (trajectory.txt, ...). */
  const COutputFiles& files() const;

  /** The writers, in the order they are told: the files come before every writer that reads their
   * trajectory, the statistics (ATE) before the truth series and the scene. */
  std::vector<IFrameSink*> sinks();

 private:
  std::vector<std::unique_ptr<IFrameSink>> m_sinks;
  const COutputFiles* m_files = nullptr;
};
}  // namespace immslam::app::detail
