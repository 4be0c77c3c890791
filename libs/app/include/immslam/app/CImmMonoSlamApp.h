/* imm-monoslam — the main application as a class (MRPT's KFSLAMApp pattern): the thin main in
 * apps/imm-monoslam calls initialize(argc, argv) and run(); tests run it end to end in-process and
 * read its results. Command line, configs and outputs: ../shared/CONTRACT.md and doc/usage.md. */
#pragma once

#include <immslam/eval/ate.h>

#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/system/COutputLogger.h>

#include <atomic>
#include <optional>
#include <string>
#include <vector>

namespace immslam::io
{
class CLiveCameraSource;
}

namespace immslam::app
{
/** Parsed command line. */
struct TAppArguments
{
  std::string config;              ///< CONFIG.ini
  std::string input;               ///< INPUT (rawlog or dataset folder), may be empty
  std::string outDir = "imm-monoslam-out";
  std::string calib;               ///< --calib FILE
  double fovDeg = 0;               ///< --fov DEG: guessed calibration when none is given or found (0: none)
  std::string live;                ///< --live GRABBER.ini[:SECTION]
  std::string record;              ///< --record FILE.rawlog (live sessions)
  long long maxFrames = -1;        ///< --frames N
  bool noGui = false;
  bool quiet = false;
  bool printConfig = false;        ///< --print-config
  std::vector<std::string> sets;   ///< --set SECTION.KEY=VALUE
};

/** What a run did (printed as the summary; read by tests). */
struct TRunSummary
{
  std::size_t framesRead = 0, framesProcessed = 0, framesSkipped = 0;
  std::size_t framesWithoutMask = 0;     ///< processed with no mask of [input] exclusion_masks (nothing excluded)
  std::size_t framesWithoutTracks = 0;   ///< processed with no measurement of [input] known_association
  std::vector<std::string> skipReasons;  ///< first few reasons
  std::string endReason;                 ///< "" for a normal end of input
  double wallSeconds = 0, fps = 0, medianFrameMs = 0, meanFrameMs = 0;
  int finalMapSize = 0;
  double medianMatched = 0;
  std::optional<eval::TAteResult> ate;   ///< against the input's ground truth, when it has one
  std::optional<eval::TAteResult> ateRefined;  ///< the same for trajectory_refined.txt ([output] refine_trajectory)
  double refineSeconds = 0;              ///< time of the final bundle adjustment
  std::optional<eval::TAteResult> ateSmoothed;  ///< the same for trajectory_smoothed.txt ([output] smooth_trajectory)
  double smoothMedianLagFrames = 0, smoothMaxLagFrames = 0;  ///< frames from a keyframe to its first smoothed pose
  double smoothCpuSeconds = 0;           ///< CPU time of the smoother's thread
  std::string outDir;
};

class CImmMonoSlamApp : public mrpt::system::COutputLogger
{
 public:
  CImmMonoSlamApp();
  ~CImmMonoSlamApp() override;

  /** Parses the command line and loads the config. \return -1 to go on with run(), or the exit
   * status to return now (0 after --help/--version, 2 on bad usage, 1 on a bad config). */
  int initialize(int argc, const char* const* argv);
  int initialize(const std::vector<std::string>& args);

  /** Runs on the input; writes every output file. \return 0 on success, 1 on bad input or failure
   * (the message names the file, key or frame). Never throws. Outputs written so far are kept. */
  int run();

  /** Asks a running run() to stop after the current frame (thread- and signal-safe; a live camera
   * waiting for a frame is told to stop too). */
  void requestStop();

  /** The loaded configuration (after --set); tests may change keys before run(). */
  mrpt::config::CConfigFileMemory& config() { return m_cfg; }
  const TAppArguments& arguments() const { return m_args; }
  const TRunSummary& summary() const { return m_summary; }

  /** Every option of every section (defaults where the config is silent), with comments. */
  std::string effectiveConfigText() const;

  static std::string usage();
  static std::string version();

 private:
  int runImpl();

  TAppArguments m_args;
  mrpt::config::CConfigFileMemory m_cfg;
  std::string m_configDir;
  TRunSummary m_summary;
  std::atomic<bool> m_stop{false};
  std::atomic<io::CLiveCameraSource*> m_live{nullptr};  ///< the live source while run() uses one
};
}  // namespace immslam::app
