/* imm-monoslam — the inputs of a run, resolved before its first frame (see run_inputs.h). */
#include "run_inputs.h"

#include <immslam/camera/mrpt_camera.h>
#include <immslam/core/config.h>
#include <immslam/io/CLiveCameraSource.h>
#include <immslam/io/CRawlogRecorder.h>
#include <immslam/io/CRawlogSource.h>
#include <immslam/sim/CSyntheticSource.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <filesystem>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace immslam::app::detail
{
namespace fs = std::filesystem;

namespace
{
/** Skipped entries logged one by one (and kept in TRunSummary::skipReasons); the rest are counted. */
constexpr std::size_t kLoggedSkips = 20;

/** A path from the config: relative to the config's folder if it exists there, else as given. */
std::string resolvePath(const std::string& p, const std::string& configDir)
{
  if (p.empty() || fs::path(p).is_absolute()) return p;
  const fs::path rel = fs::path(configDir) / p;
  if (!configDir.empty() && fs::exists(rel)) return rel.string();
  return p;
}

/** Keys of older configs that were removed or moved: an error that names the key and what replaced it. */
void checkRemovedKeys(const mrpt::config::CConfigFileBase& cfg, const std::string& section)
{
  std::vector<std::string> keys;
  cfg.getAllKeys(section, keys);
  const auto& removed = system::CMonoSlamSystem::removedKeys();
  for (const auto& k : keys)
  {
    const auto it = removed.find("[" + section + "] " + k);
    if (it != removed.end()) throw std::runtime_error("[" + section + "] " + k + ": " + it->second);
  }
}

/** Unknown sections and keys are errors that name them (removed keys with what replaced them). */
void checkConfigKeys(const mrpt::config::CConfigFileBase& cfg)
{
  auto known = system::CMonoSlamSystem::knownKeys();
  known["input"] = core::knownKeys(TInputOptions(), "input");
  known["output"] = core::knownKeys(TOutputOptions(), "output");
  const auto camKeys = camera::cameraConfigKeys();
  known["camera"] = std::set<std::string>(camKeys.begin(), camKeys.end());
  std::vector<std::string> sections;
  cfg.getAllSections(sections);
  for (const auto& s : sections)
  {
    if (s.empty()) continue;
    const auto it = known.find(s);
    if (it == known.end())
    {
      std::string list;
      for (const auto& [name, keys] : known) list += (list.empty() ? "" : ", ") + name;
      throw std::runtime_error("unknown section [" + s + "] (known: " + list + ")");
    }
    checkRemovedKeys(cfg, s);
    core::checkKnownKeys(cfg, s, it->second);
  }
}

/** The key check, then [input] and [output]; errors prefixed by the config file. */
void loadOptions(const TRunContext& ctx, TRunInputs& in)
{
  try
  {
    checkConfigKeys(ctx.cfg);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(ctx.args.config + ": " + e.what());
  }
  try
  {
    in.in.loadFromConfigFile(ctx.cfg, "input");
    in.out.loadFromConfigFile(ctx.cfg, "output");
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(ctx.args.config + ": " + e.what());
  }
}

/** Calibration given explicitly: --calib, then a [camera] section of the config. */
void explicitCalibration(const TRunContext& ctx, TRunInputs& in)
{
  if (!ctx.args.calib.empty())
  {
    in.cam = camera::loadCalibFile(ctx.args.calib);
    in.calibOrigin = ctx.args.calib;
  }
  else if (ctx.cfg.sectionExists("camera"))
  {
    try
    {
      in.cam = camera::loadCameraFromConfig(ctx.cfg, "camera");
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error(ctx.args.config + ": " + e.what());
    }
    in.calibOrigin = ctx.args.config + " [camera]";
  }
}

/** --live: the grabber (with the explicit calibration), published in `live`; --record. */
void openLiveSource(const TRunContext& ctx, TRunInputs& in, std::atomic<io::CLiveCameraSource*>& live,
                    const std::atomic<bool>& stop)
{
  const auto [ini, section] = io::splitLiveSpec(ctx.args.live);
  io::TLiveOptions lo;
  lo.frameRateHz = in.in.live_frame_rate_hz;
  lo.paced = in.in.live_paced;
  lo.camera = in.cam;
  auto owned = std::make_unique<io::CLiveCameraSource>(ini, section, lo);
  io::CLiveCameraSource& src = *owned;
  in.source = std::move(owned);
  live = &src;
  if (stop) src.requestStop();
  if (!ctx.args.record.empty())
  {
    in.recorder = std::make_shared<io::CRawlogRecorder>(ctx.args.record);
    src.setRecorder(in.recorder);
  }
}

/** Input: INPUT, --live, or the config's [input] source (a path, or `synthetic`: the scenario). */
void openSource(const TRunContext& ctx, TRunInputs& in, std::atomic<io::CLiveCameraSource*>& live,
                const std::atomic<bool>& stop)
{
  in.inputPath = ctx.args.input;
  if (!ctx.args.live.empty())
  {
    openLiveSource(ctx, in, live, stop);
    return;
  }
  if (!ctx.args.record.empty()) throw std::runtime_error("--record needs --live");
  if (in.inputPath.empty() && in.in.source != "synthetic") in.inputPath = resolvePath(in.in.source, ctx.configDir);
  if (!in.inputPath.empty())
  {
    in.source = io::openImageSource(in.inputPath, in.in.rawlog_sensor_label);
    if (const auto* rawlog = dynamic_cast<const io::CRawlogSource*>(in.source.get()))
      for (const auto& w : rawlog->warnings()) ctx.log.logStr(mrpt::system::LVL_WARN, in.inputPath + ": " + w);
  }
  else if (in.in.scenario.empty())
    in.source = std::make_unique<sim::CSyntheticSource>(sim::TScenario::builtinDefault());
  else
    in.source = std::make_unique<sim::CSyntheticSource>(resolvePath(in.in.scenario, ctx.configDir));
}

/** [input] exclusion_masks: the masks of a rendered folder. */
void loadExclusionMasks(const TRunContext& ctx, TRunInputs& in)
{
  if (in.in.exclusion_masks.empty()) return;
  const std::string dir = resolvePath(in.in.exclusion_masks, ctx.configDir);
  try
  {
    in.excludedAt = eval::maskFolderProvider(dir);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("[input] exclusion_masks = " + dir + ": " + e.what());
  }
  ctx.log.logStr(mrpt::system::LVL_INFO, "excluded pixels: masks of " + dir + " (no new feature or SLAM match there)");
}

/** [input] known_association: the measured tracks of each frame, by timestamp (microseconds). */
void loadKnownTracks(const TRunContext& ctx, TRunInputs& in)
{
  if (in.in.known_association.empty()) return;
  const std::string file = resolvePath(in.in.known_association, ctx.configDir);
  std::vector<core::TGroundTruthPoint> points;
  try
  {
    points = eval::readPointsGroundTruth(file);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error("[input] known_association = " + file + ": " + e.what());
  }
  const std::string& kinds = in.in.known_association_kinds;
  std::size_t used = 0;
  in.knownTracks = TKnownTracks::fromPoints(points, kinds, used);
  ctx.log.logStr(mrpt::system::LVL_INFO, "known data association: " + std::to_string(used) + " measurements (" +
                                             kinds + " tracks) of " + file + " instead of the image search");
}

/** The camera: the explicit one, else the source's, else --fov's guess (a placeholder until the
 * first frame gives the size). */
void decideCalibration(const TRunContext& ctx, TRunInputs& in)
{
  if (!in.cam)
  {
    in.cam = in.source->calibration();
    in.calibOrigin = "the input";
  }
  if (ctx.args.fovDeg > 0)
  {
    if (in.cam)
      ctx.log.logStr(mrpt::system::LVL_WARN, "--fov ignored: the calibration of " + in.calibOrigin + " is used");
    else
    {
      in.cam = camera::pinholeFromFieldOfView(640, 480, ctx.args.fovDeg);
      std::ostringstream fov;
      fov << ctx.args.fovDeg;
      in.calibOrigin = "guessed from --fov " + fov.str() + " at the first frame's size";
      in.guessCalibration = true;
    }
  }
  if (!in.cam)
    throw std::runtime_error("no camera calibration: the input has none; give --calib FILE (calib.txt format), a "
                             "[camera] section in " + ctx.args.config + ", or --fov DEG to guess one");
  in.calibAsGiven = in.guessCalibration ? in.calibOrigin + " (calib_guessed.txt)" : in.cam->toCalibLine();
  if (!in.guessCalibration)
    ctx.log.logStr(mrpt::system::LVL_INFO, "camera (" + in.calibOrigin + "): " + in.cam->toCalibLine());
}
}  // namespace

void resolveInputs(const TRunContext& ctx, TRunInputs& in, std::atomic<io::CLiveCameraSource*>& live,
                   const std::atomic<bool>& stop)
{
  loadOptions(ctx, in);
  explicitCalibration(ctx, in);
  openSource(ctx, in, live, stop);
  ctx.log.logStr(mrpt::system::LVL_INFO, "input: " + in.source->describe());
  loadExclusionMasks(ctx, in);
  loadKnownTracks(ctx, in);
  decideCalibration(ctx, in);
}

void countSkip(const TRunContext& ctx, TRunSummary& summary, const std::string& reason)
{
  ++summary.framesSkipped;
  // The first kLoggedSkips reasons are logged and kept; a rawlog of many sensors (IMU at 200 Hz, a second
  // camera) would otherwise bury the log: the rest are counted (summary line).
  if (summary.skipReasons.size() < kLoggedSkips)
  {
    summary.skipReasons.push_back(reason);
    ctx.log.logStr(mrpt::system::LVL_WARN, "skipped: " + reason);
    if (summary.skipReasons.size() == kLoggedSkips)
      ctx.log.logStr(mrpt::system::LVL_WARN, "further skipped entries are counted, not logged");
  }
}
}  // namespace immslam::app::detail
