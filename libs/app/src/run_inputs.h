/* imm-monoslam — private to libs/app: what a run decides before its first frame (options, camera
 * calibration, image source, exclusion masks, known data association). */
#pragma once

#include <immslam/app/CImmMonoSlamApp.h>
#include <immslam/app/app_options.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/eval/classification_truth.h>
#include <immslam/io/CImageSource.h>

#include "TKnownTracks.h"

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/system/COutputLogger.h>

#include <atomic>
#include <memory>
#include <optional>
#include <string>

namespace immslam::io
{
class CRawlogRecorder;
}

namespace immslam::app::detail
{
/** What the steps of a run read from the application: command line, configuration, log. */
struct TRunContext
{
  const TAppArguments& args;                  ///< the command line
  const mrpt::config::CConfigFileBase& cfg;   ///< the configuration (after --set)
  const std::string& configDir;               ///< folder of the config file (relative paths)
  mrpt::system::COutputLogger& log;           ///< the application's log
};

/** The inputs of a run, resolved before its first frame (resolveInputs()). */
struct TRunInputs
{
  TInputOptions in;                              ///< [input]
  TOutputOptions out;                            ///< [output]
  camera::CCameraModel::Ptr cam;                 ///< the calibration (a placeholder while guessCalibration)
  std::string calibOrigin;                       ///< where cam comes from, for the log
  std::string calibAsGiven;                      ///< the calibration before the first frame (config_effective.ini)
  bool guessCalibration = false;                 ///< --fov: cam is guessed again at the first frame's size
  io::CImageSource::Ptr source;                  ///< INPUT, --live, [input] source or the built-in scene
  std::shared_ptr<io::CRawlogRecorder> recorder; ///< --record (live input only)
  std::string inputPath;                         ///< INPUT, else the [input] source path (empty: rendered scene, --live)
  eval::TMaskProvider excludedAt;                ///< [input] exclusion_masks (empty: none)
  std::optional<TKnownTracks> knownTracks;       ///< [input] known_association (none: image search)
};

/** Resolves the inputs of a run, in this order: the config's sections and keys (unknown ones are
 * errors), [input] and [output]; the explicit calibration (--calib, else [camera]); the source
 * (--live, INPUT, [input] source, else the rendered scene; logged); exclusion masks and known data
 * association ([input]); the camera (the explicit one, else the source's, else --fov's guess).
 * A live source is published in `live` as soon as `in` owns it (the caller clears `live` before
 * `in` goes), and told to stop at once if `stop` is already set.
 * \throws std::runtime_error naming the file, key or option at fault. */
void resolveInputs(const TRunContext& ctx, TRunInputs& in, std::atomic<io::CLiveCameraSource*>& live,
                   const std::atomic<bool>& stop);

/** Counts a skipped input entry in `summary`; the first few reasons are logged and kept. */
void countSkip(const TRunContext& ctx, TRunSummary& summary, const std::string& reason);
}  // namespace immslam::app::detail
