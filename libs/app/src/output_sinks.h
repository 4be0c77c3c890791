/* imm-monoslam — private to libs/app: the writers of a run, one IFrameSink each (CRunOutputs picks
 * and orders them): the per-frame files, the run's statistics, the final bundle adjustment, the
 * overlays, the live windows, the scenes, the truth series (for the figures), the progress line. */
#pragma once

#include <immslam/app/CLiveView.h>
#include <immslam/app/COutputFiles.h>
#include <immslam/app/app_options.h>
#include <immslam/eval/search_nis.h>
#include <immslam/viz/COverlayWriter.h>
#include <immslam/viz/scene.h>

#include "CTrajectorySmoothing.h"
#include "IFrameSink.h"
#include "run_inputs.h"

#include <chrono>
#include <cstdint>
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
/** trajectory.txt, model_probabilities.csv, frame_stats.csv, ... every frame; map.csv at the end.
 * Its trajectory is the one the other writers read: it comes first. */
class CFilesSink : public IFrameSink
{
 public:
  CFilesSink(const TRunContext& ctx, const TRunInputs& in, const system::CMonoSlamSystem& sys);
  void onFrame(const TFrameResult& r) override;
  void onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary) override;
  const COutputFiles& files() const { return m_files; }

 private:
  COutputFiles m_files;
};

/** The summary's figures: frame times and match counts, final map size, the ATE against the
 * input's ground truth; warnings for frames without mask or known tracks. */
class CStatisticsSink : public IFrameSink
{
 public:
  CStatisticsSink(const TRunContext& ctx, const TRunInputs& in, const core::TTrajectory& trajectory);
  void onFrame(const TFrameResult& r) override;
  void onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary) override;

 private:
  const TRunContext& m_ctx;
  const TRunInputs& m_in;
  const core::TTrajectory& m_trajectory;
  std::vector<double> m_frameMs, m_matched;  ///< per processed frame
};

/** [output] smooth_trajectory: the online keyframe smoother (its own thread; this writer only hands
 * each frame's pose and matches over) and trajectory_smoothed.txt at the end. */
class CSmoothingSink : public IFrameSink
{
 public:
  CSmoothingSink(const TRunInputs& in, const COutputFiles& files, mrpt::system::COutputLogger& log);
  void onFrame(const TFrameResult& r) override;
  void onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary) override;
  /** The smoothed trajectory once onEnd() has run (empty before). */
  const core::TTrajectory& trajectory() const { return m_smoothing.trajectory(); }
  /** What the scenes draw: the keyframes smoothed so far, then the whole smoothed trajectory. */
  core::TTrajectory published() const { return m_smoothing.published(); }

 private:
  const TRunInputs& m_in;
  const COutputFiles& m_files;
  mrpt::system::COutputLogger& m_log;
  CTrajectorySmoothing m_smoothing;
};

/** [output] refine_trajectory: the inlier matches of every frame, then trajectory_refined.txt, a
 * bundle adjustment of them started at the smoothed trajectory when the run smooths (its sink's
 * onEnd() must come first), else at the filter's (and its ATE). */
class CRefineSink : public IFrameSink
{
 public:
  CRefineSink(const TRunContext& ctx, const TRunInputs& in, const COutputFiles& files,
              const CSmoothingSink* smoothing);
  void onFrame(const TFrameResult& r) override;
  void onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary) override;

 private:
  const TRunContext& m_ctx;
  const TRunInputs& m_in;
  const COutputFiles& m_files;
  const CSmoothingSink* m_smoothing;     ///< null: the run does not smooth
  std::vector<eval::TSearchRow> m_rows;  ///< matches used in the updates, and held-back ones
  std::vector<double> m_stamps;          ///< timestamp of every frame so far
};

/** The progress line on a terminal, at most every 0.2 s (frame, rate, map, matches, dominant model,
 * time left when the input's size is known). */
class CProgressSink : public IFrameSink
{
 public:
  CProgressSink(const TRunSummary& summary, std::size_t total);
  void onFrame(const TFrameResult& r) override;
  void onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary) override;

 private:
  using Clock = std::chrono::steady_clock;
  const TRunSummary& m_summary;
  std::size_t m_total;  ///< the source's size hint (0: unknown)
  Clock::time_point m_start, m_last;
};

/** The dynamic tracks seen so far (world positions by id), drawn in the scenes. */
struct TTrackHistory
{
  std::map<std::int64_t, std::vector<Vec3>> lines;
  /** Adds the measured shadow tracks of a frame. */
  void add(const system::TSystemFrame& fr);
};

/** The scene of the current state: trajectory, camera, map with uncertainties, the dynamic tracks
 * near the map, and the smoother's trajectory so far when the run smooths (`smoothing` not null). */
viz::TSceneContent sceneContent(const slam::CMonoSlamIMM& slam, const core::TTrajectory& trajectory,
                                const TTrackHistory& tracks, const std::string& title,
                                const CSmoothingSink* smoothing);

/** [output] overlays, overlay_video: overlays/ and overlays.avi every overlay_every_n frames. */
class COverlaySink : public IFrameSink
{
 public:
  COverlaySink(const std::string& outDir, const TOutputOptions& opts);
  void onFrame(const TFrameResult& r) override;
  void onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary) override;

 private:
  viz::COverlayWriter m_writer;
  std::size_t m_everyN;
};

/** The live windows (CLiveView): the overlay every frame, the scene every gui_scene_every_n. */
class CLiveViewSink : public IFrameSink
{
 public:
  CLiveViewSink(const TOutputOptions& opts, const core::TTrajectory& trajectory, const CSmoothingSink* smoothing);
  void onFrame(const TFrameResult& r) override;
  void onEnd(const slam::CMonoSlamIMM&, TRunSummary&) override {}

 private:
  CLiveView m_view;
  std::size_t m_sceneEveryN;
  const core::TTrajectory& m_trajectory;
  const CSmoothingSink* m_smoothing;  ///< null: the run does not smooth
  TTrackHistory m_tracks;
};

/** [output] scene_every_n: scene_NNNNNN.3Dscene and .png; [output] scene: scene.3Dscene and
 * scene.png at the end, with the ground truth aligned by the summary's ATE. */
class CSceneSink : public IFrameSink
{
 public:
  CSceneSink(const TRunContext& ctx, const TRunInputs& in, const core::TTrajectory& trajectory,
             const CSmoothingSink* smoothing);
  void onFrame(const TFrameResult& r) override;
  void onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary) override;

 private:
  const TRunContext& m_ctx;
  const TRunInputs& m_in;
  const core::TTrajectory& m_trajectory;
  const CSmoothingSink* m_smoothing;  ///< null: the run does not smooth (ends before this sink)
  TTrackHistory m_tracks;
};

/** The series the figures of a run need beyond the per-frame files (share/scripts/plot-run.py draws
 * them): motion_labels.csv (`timestamp,label`, the true motion of each frame) when the input knows it
 * (rendered scenarios; dataset folders with motion_labels.txt), ate.csv (`timestamp,position_error`,
 * after Sim(3) alignment) when it has ground truth. Timestamps are those of model_probabilities.csv. */
class CTruthSeriesSink : public IFrameSink
{
 public:
  CTruthSeriesSink(const TRunContext& ctx, const TRunInputs& in);
  void onFrame(const TFrameResult& r) override;
  void onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary) override;

 private:
  const TRunContext& m_ctx;
  const TRunInputs& m_in;
  const sim::CSyntheticSource* m_synthetic;          ///< the source, when it is the renderer
  std::map<long long, std::string> m_folderLabels;   ///< motion_labels.txt of a dataset folder
  std::vector<std::pair<double, std::string>> m_labels;  ///< (timestamp, true label) of labelled frames
};
}  // namespace immslam::app::detail
