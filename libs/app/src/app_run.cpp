/* imm-monoslam — the run loop of the main application: input selection, calibration, the system
 * per frame, outputs, progress and summary. */
#include <immslam/app/CImmMonoSlamApp.h>
#include <immslam/app/COutputFiles.h>
#include <immslam/app/CVisualOutputs.h>
#include <immslam/app/app_options.h>
#include <immslam/camera/mrpt_camera.h>
#include <immslam/core/config.h>
#include <immslam/eval/classification_truth.h>
#include <immslam/eval/reprojection.h>
#include <immslam/eval/statistics.h>
#include <immslam/io/CImageSource.h>
#include <immslam/io/CLiveCameraSource.h>
#include <immslam/io/CRawlogSource.h>
#include <immslam/io/CRawlogRecorder.h>
#include <immslam/sim/CSyntheticSource.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <mrpt/config/CConfigFile.h>
#include <opencv2/imgproc.hpp>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <set>
#include <iostream>
#include <limits>
#include <sstream>

namespace immslam::app
{
namespace fs = std::filesystem;

namespace
{
/** Skipped entries logged one by one (and kept in TRunSummary::skipReasons); the rest are counted. */
constexpr std::size_t kLoggedSkips = 20;
/** [input] max_image_width: the power-of-two reduction that brings the first frame's width to the
 * limit. A side the factor does not divide loses its last (at most factor - 1) columns or rows first,
 * which leaves the intrinsics as they are, so the scaled calibration is exact. Frames of another size
 * than the first are left alone (the size check skips them). */
struct TImageReduction
{
  int factor = 0;  ///< 0: not decided yet; 1: none
  cv::Size full;   ///< the first frame's size
  cv::Rect kept;   ///< the part of a full-size frame that is reduced

  TImageReduction() = default;
  TImageReduction(cv::Size first, int maxWidth) : factor(1), full(first)
  {
    while (maxWidth > 0 && full.width / factor > maxWidth) factor *= 2;
    kept = cv::Rect(0, 0, full.width - full.width % factor, full.height - full.height % factor);
  }
  bool decided() const { return factor > 0; }
  std::string describe(int maxWidth) const
  {
    std::ostringstream s;
    s << "images are " << full.width << "x" << full.height << ": processed at " << kept.width / factor << "x"
      << kept.height / factor << " ([input] max_image_width = " << maxWidth << ")";
    if (kept.size() != full) s << ", after dropping their last columns/rows to " << kept.width << "x" << kept.height;
    return s.str();
  }
  /** The calibration of a full-size frame for the reduced one. */
  camera::CCameraModel::Ptr camera(const camera::CCameraModel& c) const
  {
    return camera::makeCameraModel(c.modelName(), kept.width, kept.height, c.parameters())->scaled(1.0 / factor);
  }
  void apply(io::TFrame& f) const
  {
    if (factor <= 1 || f.grey.size() != full) return;
    const cv::Size small(kept.width / factor, kept.height / factor);
    cv::resize(f.grey(kept), f.grey, small, 0, 0, cv::INTER_AREA);
    if (!f.colour.empty()) cv::resize(f.colour(kept), f.colour, small, 0, 0, cv::INTER_AREA);
  }
  /** A full-size exclusion mask for the reduced frame: a reduced pixel is excluded if any of the
   * full-size pixels it averages is. */
  cv::Mat applyToMask(const cv::Mat& m) const
  {
    if (factor <= 1 || m.size() != full) return m;
    cv::Mat small;
    cv::resize(m(kept), small, cv::Size(kept.width / factor, kept.height / factor), 0, 0, cv::INTER_AREA);
    return small != 0;
  }
};

/** [input] known_association: the measured point tracks, by frame time. */
struct TKnownTracks
{
  std::map<long long, std::vector<std::pair<std::int64_t, Vec2>>> byTime;  ///< microseconds -> (track, pixel)
  std::set<std::int64_t> moving;                                            ///< tracks of kind moving

  /** The tracks of the frame at t (within 0.1 ms), in the pixels of the image reduced by `factor`;
   * staticOnly: without the moving ones (a static first map). */
  std::vector<std::pair<std::int64_t, Vec2>> at(double t, int factor, bool staticOnly) const
  {
    std::vector<std::pair<std::int64_t, Vec2>> z;
    const long long us = std::llround(t * 1e6);
    for (auto it = byTime.lower_bound(us - 100); it != byTime.end() && it->first <= us + 100; ++it)
      for (const auto& [id, uv] : it->second)
        if (!staticOnly || !moving.count(id)) z.emplace_back(id, factor > 1 ? Vec2(uv / factor) : uv);
    return z;
  }
};

/** [input] exclusion_masks: the mask of a frame (non-zero: excluded) at the processed image size, or
 * an empty image when the folder has none for the frame's timestamp.
 * \throws std::runtime_error naming the frame and the key for a mask of another size. */
cv::Mat exclusionMaskFor(const eval::TMaskProvider& maskAt, const io::TFrame& frame, const TImageReduction& reduction)
{
  const std::optional<eval::TMaskImage> m = maskAt(frame.timestamp);
  if (!m) return cv::Mat();
  cv::Mat mask(m->height, m->width, CV_8UC1, const_cast<std::uint8_t*>(m->pixels.data()));
  mask = reduction.applyToMask(mask != 0);
  if (mask.size() != frame.grey.size())
  {
    const cv::Size image = reduction.factor > 1 ? reduction.full : frame.grey.size();
    std::ostringstream s;
    s << "frame " << frame.index << " (" << frame.origin << "): [input] exclusion_masks: mask of " << m->width << "x"
      << m->height << " pixels for an image of " << image.width << "x" << image.height;
    throw std::runtime_error(s.str());
  }
  return mask;
}

/** A path from the config: relative to the config's folder if it exists there, else as given. */
std::string resolvePath(const std::string& p, const std::string& configDir)
{
  if (p.empty() || fs::path(p).is_absolute()) return p;
  const fs::path rel = fs::path(configDir) / p;
  if (!configDir.empty() && fs::exists(rel)) return rel.string();
  return p;
}

/** True motion labels of a rendered dataset folder (motion_labels.txt: "timestamp label"), if any. */
std::map<long long, std::string> readMotionLabels(const std::string& folder)
{
  std::map<long long, std::string> out;
  std::ifstream f(fs::path(folder) / "motion_labels.txt");
  std::string line;
  while (std::getline(f, line))
  {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    double t;
    std::string label;
    if (is >> t >> label) out[std::llround(t * 1e6)] = label;
  }
  return out;
}

/** Unknown sections and keys are errors that name them. */
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
    core::checkKnownKeys(cfg, s, it->second);
  }
}

std::string formatSeconds(double s)
{
  std::ostringstream o;
  if (s >= 60)
    o << static_cast<int>(s / 60) << "m" << std::setw(2) << std::setfill('0') << static_cast<int>(s) % 60 << "s";
  else
    o << std::fixed << std::setprecision(0) << s << "s";
  return o.str();
}

/** [output] refine_trajectory: bundle adjustment of the run's own matches (the filter's trajectory as
 * the start), written to trajectory_refined.txt, with its ATE when the input has ground truth. */
void refineTrajectory(const std::vector<eval::TSearchRow>& rows, const COutputFiles& out,
                      const camera::CCameraModel& cam, const std::optional<core::TTrajectory>& gt,
                      TRunSummary& summary, mrpt::system::COutputLogger& log)
{
  const auto t0 = std::chrono::steady_clock::now();
  try
  {
    eval::TBundleProblem prob = eval::makeBundleProblem(rows, out.trajectory(), cam, 1e-6, 8, 6);
    const double before = eval::reprojectionStats(prob).rmsPx;
    const eval::TBundleResult r = eval::bundleAdjust(prob);
    const double after = eval::reprojectionStats(prob).rmsPx;
    core::writeTumTrajectory(prob.poses, out.path("trajectory_refined.txt"));
    summary.refineSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::ostringstream m;
    m << std::fixed << std::setprecision(3) << "trajectory_refined.txt: " << prob.poses.size() << " poses, "
      << prob.points.size() << " features, " << prob.obs.size() << " matches; reprojection RMS " << before << " -> "
      << after << " px in " << r.iterations << " iterations, " << std::setprecision(2) << summary.refineSeconds
      << " s";
    if (r.components > 1) m << "; " << r.components << " unrelated blocks (the run started new maps), each in its own frame";
    log.logStr(mrpt::system::LVL_INFO, m.str());
    if (gt && prob.poses.size() >= 3) summary.ateRefined = eval::computeAte(prob.poses, *gt, eval::EAlignment::Sim3, 0.01);
  }
  catch (const std::exception& e)
  {
    log.logStr(mrpt::system::LVL_WARN, std::string("no refined trajectory: ") + e.what());
  }
}
}  // namespace

int CImmMonoSlamApp::run()
{
  try
  {
    return runImpl();
  }
  catch (const std::exception& e)
  {
    std::cerr << "imm-monoslam: error: " << e.what() << "\n";
    return 1;
  }
}

int CImmMonoSlamApp::runImpl()
{
  using Clock = std::chrono::steady_clock;
  m_summary = TRunSummary();
  m_summary.outDir = m_args.outDir;
  try
  {
    checkConfigKeys(m_cfg);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(m_args.config + ": " + e.what());
  }
  TInputOptions inOpts;
  TOutputOptions outOpts;
  try
  {
    inOpts.loadFromConfigFile(m_cfg, "input");
    outOpts.loadFromConfigFile(m_cfg, "output");
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(m_args.config + ": " + e.what());
  }

  // ---- Calibration given explicitly: --calib, then a [camera] section of the config.
  camera::CCameraModel::Ptr cam;
  std::string calibOrigin;
  if (!m_args.calib.empty())
  {
    cam = camera::loadCalibFile(m_args.calib);
    calibOrigin = m_args.calib;
  }
  else if (m_cfg.sectionExists("camera"))
  {
    try
    {
      cam = camera::loadCameraFromConfig(m_cfg, "camera");
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error(m_args.config + ": " + e.what());
    }
    calibOrigin = m_args.config + " [camera]";
  }

  // ---- Input: INPUT, --live, or the config's [input] source.
  io::CImageSource::Ptr source;
  // The live source is published to requestStop() while it exists: the guard, declared after the
  // source, clears it before the source is destroyed, on every way out.
  struct TLiveGuard
  {
    std::atomic<io::CLiveCameraSource*>& p;
    ~TLiveGuard() { p = nullptr; }
  } liveGuard{m_live};
  std::shared_ptr<io::CRawlogRecorder> recorder;
  std::string inputPath = m_args.input;
  if (!m_args.live.empty())
  {
    const auto [ini, section] = io::splitLiveSpec(m_args.live);
    io::TLiveOptions lo;
    lo.frameRateHz = inOpts.live_frame_rate_hz;
    lo.camera = cam;
    auto live = std::make_unique<io::CLiveCameraSource>(ini, section, lo);
    m_live = live.get();
    if (m_stop) live->requestStop();
    if (!m_args.record.empty())
    {
      recorder = std::make_shared<io::CRawlogRecorder>(m_args.record);
      live->setRecorder(recorder);
    }
    source = std::move(live);
  }
  else
  {
    if (!m_args.record.empty()) throw std::runtime_error("--record needs --live");
    if (inputPath.empty() && inOpts.source != "synthetic") inputPath = resolvePath(inOpts.source, m_configDir);
    if (!inputPath.empty())
    {
      source = io::openImageSource(inputPath, inOpts.rawlog_sensor_label);
      if (const auto* rawlog = dynamic_cast<const io::CRawlogSource*>(source.get()))
        for (const auto& w : rawlog->warnings()) logStr(mrpt::system::LVL_WARN, inputPath + ": " + w);
    }
    else if (inOpts.scenario.empty())
      source = std::make_unique<sim::CSyntheticSource>(sim::TScenario::builtinDefault());
    else
      source = std::make_unique<sim::CSyntheticSource>(resolvePath(inOpts.scenario, m_configDir));
  }
  logStr(mrpt::system::LVL_INFO, "input: " + source->describe());
  eval::TMaskProvider excludedAt;
  if (!inOpts.exclusion_masks.empty())
  {
    const std::string dir = resolvePath(inOpts.exclusion_masks, m_configDir);
    try
    {
      excludedAt = eval::maskFolderProvider(dir);
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error("[input] exclusion_masks = " + dir + ": " + e.what());
    }
    logStr(mrpt::system::LVL_INFO, "excluded pixels: masks of " + dir + " (no new feature or SLAM match there)");
  }
  // [input] known_association: the measured tracks of each frame, by timestamp (microseconds).
  TKnownTracks knownTracks;
  const bool knownAssociation = !inOpts.known_association.empty();
  if (knownAssociation)
  {
    const std::string file = resolvePath(inOpts.known_association, m_configDir);
    std::vector<core::TGroundTruthPoint> points;
    try
    {
      points = eval::readPointsGroundTruth(file);
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error("[input] known_association = " + file + ": " + e.what());
    }
    const std::string& kinds = inOpts.known_association_kinds;
    std::size_t used = 0;
    for (const auto& p : points)
      if (kinds == "all" || (kinds == "moving") == p.moving)
      {
        knownTracks.byTime[std::llround(p.timestamp * 1e6)].emplace_back(p.pointId, p.uv);
        if (p.moving) knownTracks.moving.insert(p.pointId);
        ++used;
      }
    logStr(mrpt::system::LVL_INFO, "known data association: " + std::to_string(used) + " measurements (" + kinds +
                                       " tracks) of " + file + " instead of the image search");
  }
  if (!cam)
  {
    cam = source->calibration();
    calibOrigin = "the input";
  }
  // --fov: no calibration anywhere, a guess of the first frame's size (a placeholder until then).
  bool guessCalibration = false;
  if (m_args.fovDeg > 0)
  {
    if (cam)
      logStr(mrpt::system::LVL_WARN, "--fov ignored: the calibration of " + calibOrigin + " is used");
    else
    {
      cam = camera::pinholeFromFieldOfView(640, 480, m_args.fovDeg);
      std::ostringstream fov;
      fov << m_args.fovDeg;
      calibOrigin = "guessed from --fov " + fov.str() + " at the first frame's size";
      guessCalibration = true;
    }
  }
  if (!cam)
    throw std::runtime_error("no camera calibration: the input has none; give --calib FILE (calib.txt format), a "
                             "[camera] section in " + m_args.config + ", or --fov DEG to guess one");
  if (!guessCalibration) logStr(mrpt::system::LVL_INFO, "camera (" + calibOrigin + "): " + cam->toCalibLine());

  // ---- System and outputs
  std::unique_ptr<system::CMonoSlamSystem> sys;
  try
  {
    sys = std::make_unique<system::CMonoSlamSystem>(m_cfg, cam);
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(m_args.config + ": " + e.what());
  }
  COutputFiles out(m_args.outDir, sys->slam(), sys->shadowFilter() != nullptr, outOpts.search_log);
  CVisualOutputs visuals(m_args.outDir, outOpts, sys->slam(), CLiveView::available(m_args.noGui));
  // True motion labels per processed frame, when the input knows them (for the probability plot).
  auto* synthetic = dynamic_cast<sim::CSyntheticSource*>(source.get());
  const auto folderLabels = inputPath.empty() ? std::map<long long, std::string>() : readMotionLabels(inputPath);
  std::vector<std::string> labels;
  {
    // The effective configuration, printed and saved with every run.
    const std::string eff = effectiveConfigText();
    std::ofstream f(out.path("config_effective.ini"));
    f << "# Effective configuration of this run (" << version() << ")\n# config: " << m_args.config << "\n# camera: "
      << (guessCalibration ? calibOrigin + " (calib_guessed.txt)" : cam->toCalibLine()) << "\n"
      << eff;
    if (!m_args.quiet) logStr(mrpt::system::LVL_DEBUG, "effective configuration:\n" + eff);
  }

  // ---- Frames
  // The matches used in the updates, kept for the final bundle adjustment ([output] refine_trajectory).
  std::vector<eval::TSearchRow> refineRows;
  const bool tty = !m_args.quiet && isatty(fileno(stderr));
  const std::size_t total = source->sizeHint();
  std::vector<double> frameMs, matched;
  const auto tStart = Clock::now();
  auto lastProgress = tStart;
  io::TFrame frame;
  std::string why;
  double lastTimestamp = -std::numeric_limits<double>::infinity();
  TImageReduction reduction;  // [input] max_image_width, decided at the first frame
  for (;;)
  {
    if (m_stop)
    {
      m_summary.endReason = "stopped by user";
      break;
    }
    if (m_args.maxFrames >= 0 && static_cast<long long>(m_summary.framesProcessed) >= m_args.maxFrames) break;
    const io::ENextStatus st = source->next(frame, why);
    if (st == io::ENextStatus::End)
    {
      m_summary.endReason = why;
      break;
    }
    ++m_summary.framesRead;
    auto skip = [&](const std::string& reason) {
      ++m_summary.framesSkipped;
      // The first kLoggedSkips reasons are logged and kept; a rawlog of many sensors (IMU at 200 Hz, a second
      // camera) would otherwise bury the log: the rest are counted (summary line).
      if (m_summary.skipReasons.size() < kLoggedSkips)
      {
        m_summary.skipReasons.push_back(reason);
        logStr(mrpt::system::LVL_WARN, "skipped: " + reason);
        if (m_summary.skipReasons.size() == kLoggedSkips)
          logStr(mrpt::system::LVL_WARN, "further skipped entries are counted, not logged");
      }
    };
    if (st == io::ENextStatus::Skipped)
    {
      skip(why);
      continue;
    }
    if (!(frame.timestamp > lastTimestamp))
    {
      // Time must run forward: the motion models integrate over it and the outputs are time series.
      std::ostringstream s;
      s.precision(9);
      s << "frame " << frame.index << " (" << frame.origin << "): timestamp " << frame.timestamp
        << " is not after the previous frame's " << lastTimestamp;
      skip(s.str());
      continue;
    }
    if (m_summary.framesProcessed == 0 && !reduction.decided())
    {
      reduction = TImageReduction(frame.grey.size(), inOpts.max_image_width);
      if (reduction.factor > 1)
      {
        logStr(mrpt::system::LVL_INFO, reduction.describe(inOpts.max_image_width));
        if (cam && cam->width() == reduction.full.width && cam->height() == reduction.full.height)
        {
          cam = reduction.camera(*cam);
          sys = std::make_unique<system::CMonoSlamSystem>(m_cfg, cam);
          logStr(mrpt::system::LVL_INFO, "camera (" + calibOrigin + ", scaled): " + cam->toCalibLine());
        }
      }
    }
    reduction.apply(frame);
    if (guessCalibration)
    {
      // The guessed pinhole at this frame's size, kept for a re-run with --calib.
      guessCalibration = false;
      cam = camera::pinholeFromFieldOfView(frame.grey.cols, frame.grey.rows, m_args.fovDeg);
      sys = std::make_unique<system::CMonoSlamSystem>(m_cfg, cam);
      camera::saveCalibFile(*cam, out.path("calib_guessed.txt"));
      logStr(mrpt::system::LVL_INFO, "camera (" + calibOrigin + "): " + cam->toCalibLine());
    }
    if (frame.grey.cols != cam->width() || frame.grey.rows != cam->height())
    {
      // A uniformly resampled image of the calibrated camera is accepted with the scaled model.
      const double sx = static_cast<double>(frame.grey.cols) / cam->width();
      const double sy = static_cast<double>(frame.grey.rows) / cam->height();
      if (m_summary.framesProcessed == 0 && std::abs(sx - sy) < 1e-9 && sx > 0)
      {
        logStr(mrpt::system::LVL_WARN, "images are " + std::to_string(frame.grey.cols) + "x" +
                                           std::to_string(frame.grey.rows) + ": using the calibration scaled by " +
                                           std::to_string(sx));
        cam = cam->scaled(sx);
        sys = std::make_unique<system::CMonoSlamSystem>(m_cfg, cam);
      }
      else
      {
        std::ostringstream s;
        s << "frame " << frame.index << " (" << frame.origin << "): image " << frame.grey.cols << "x"
          << frame.grey.rows << " does not match the calibration's " << cam->width() << "x" << cam->height();
        skip(s.str());
        continue;
      }
    }
    cv::Mat excluded;
    if (excludedAt)
    {
      excluded = exclusionMaskFor(excludedAt, frame, reduction);
      if (excluded.empty() && m_summary.framesWithoutMask++ == 0)
        logStr(mrpt::system::LVL_WARN, "frame " + std::to_string(frame.index) + " (" + frame.origin +
                                           "): no exclusion mask for its timestamp; such frames exclude nothing");
    }
    const system::TSystemFrame* fr = nullptr;
    try
    {
      if (knownAssociation)
      {
        const bool staticOnly = m_summary.framesProcessed == 0 && inOpts.known_association_first_map == "static";
        const auto z = knownTracks.at(frame.timestamp, reduction.factor, staticOnly);
        if (z.empty() && m_summary.framesWithoutTracks++ == 0)
          logStr(mrpt::system::LVL_WARN, "frame " + std::to_string(frame.index) + " (" + frame.origin +
                                             "): no track of [input] known_association at its timestamp");
        fr = &sys->processMeasurements(frame.timestamp, z, inOpts.known_association_robust);
      }
      else
        fr = &sys->processFrame(frame.timestamp, frame.grey, excluded);
    }
    catch (const std::exception& e)
    {
      throw std::runtime_error("frame " + std::to_string(frame.index) + " (" + frame.origin + "): " + e.what());
    }
    out.addFrame(*fr, sys->slam());
    visuals.onFrame(m_summary.framesProcessed, frame.colour.empty() ? frame.grey : frame.colour, *fr, sys->slam(),
                    out.trajectory());
    if (outOpts.plots)  // the true labels are only drawn in the probability plot
    {
      if (synthetic)
        labels.push_back(sim::toString(synthetic->label(frame.index)));
      else if (const auto it = folderLabels.find(std::llround(frame.timestamp * 1e6)); it != folderLabels.end())
        labels.push_back(it->second);
    }
    if (outOpts.refine_trajectory)
      for (const auto& sr : fr->slam->searches)
        if (sr.status == slam::TSearchRecord::EStatus::LowInnovationInlier ||
            sr.status == slam::TSearchRecord::EStatus::RescuedInlier)
        {
          eval::TSearchRow row;
          row.timestamp = fr->slam->timestamp;
          row.featureId = sr.id;
          row.h = sr.h;
          row.S = sr.S;
          row.found = true;
          row.z = sr.z;
          row.score = sr.score;
          row.status = sr.status == slam::TSearchRecord::EStatus::RescuedInlier ? eval::ESearchStatus::Rescued
                                                                                : eval::ESearchStatus::Inlier;
          refineRows.push_back(row);
        }
    ++m_summary.framesProcessed;
    lastTimestamp = frame.timestamp;
    frameMs.push_back(fr->totalMs);
    matched.push_back(fr->slam->nMatched);

    if (tty && std::chrono::duration<double>(Clock::now() - lastProgress).count() > 0.2)
    {
      lastProgress = Clock::now();
      const double el = std::chrono::duration<double>(lastProgress - tStart).count();
      const double fps = m_summary.framesProcessed / std::max(el, 1e-9);
      const VecX mu = sys->slam().modelProbabilities();
      int best = 0;
      mu.maxCoeff(&best);
      std::fprintf(stderr, "\rframe %zu%s  %.1f fps  map %d  matched %d  %s %.2f", m_summary.framesRead,
                   total ? ("/" + std::to_string(total)).c_str() : "", fps, fr->slam->nMap, fr->slam->nMatched,
                   sys->slam().models()[best].name.c_str(), mu[best]);
      if (total > m_summary.framesRead)
        std::fprintf(stderr, "  ETA %s", formatSeconds((total - m_summary.framesRead) / std::max(fps, 1e-9)).c_str());
      std::fprintf(stderr, "   ");
    }
  }
  if (tty) std::fprintf(stderr, "\n");
  if (recorder) recorder->close();
  m_summary.wallSeconds = std::chrono::duration<double>(Clock::now() - tStart).count();

  // ---- Final outputs and summary
  if (m_summary.framesWithoutMask > 0)
    logStr(mrpt::system::LVL_WARN, "[input] exclusion_masks: " + std::to_string(m_summary.framesWithoutMask) +
                                       " frame(s) had no mask for their timestamp and excluded nothing");
  if (m_summary.framesWithoutTracks > 0)
    logStr(mrpt::system::LVL_WARN, "[input] known_association: " + std::to_string(m_summary.framesWithoutTracks) +
                                       " frame(s) had no track at their timestamp (prediction only)");
  out.writeMap(sys->slam());
  m_summary.finalMapSize = static_cast<int>(sys->slam().features().size());
  if (!frameMs.empty())
  {
    m_summary.medianFrameMs = eval::median(frameMs);
    m_summary.meanFrameMs = eval::mean(frameMs);
    m_summary.medianMatched = eval::median(matched);
    m_summary.fps = 1000.0 / std::max(m_summary.meanFrameMs, 1e-9);
  }
  if (const auto gt = source->groundTruth(); gt && out.trajectory().size() >= 3)
  {
    try
    {
      m_summary.ate = eval::computeAte(out.trajectory(), *gt, eval::EAlignment::Sim3, 0.01);
    }
    catch (const std::exception& e)
    {
      logStr(mrpt::system::LVL_WARN, std::string("no ATE: ") + e.what());
    }
  }
  if (outOpts.refine_trajectory) refineTrajectory(refineRows, out, *cam, source->groundTruth(), m_summary, *this);
  std::vector<std::string> warnings;
  visuals.finish(sys->slam(), out.trajectory(), source->groundTruth(), m_summary.ate, labels, warnings);
  for (const auto& w : warnings) logStr(mrpt::system::LVL_WARN, w);
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << "frames " << m_summary.framesProcessed << " processed";
  if (m_summary.framesSkipped) s << ", " << m_summary.framesSkipped << " skipped";
  if (m_summary.framesWithoutMask) s << ", " << m_summary.framesWithoutMask << " without exclusion mask";
  if (m_summary.framesWithoutTracks) s << ", " << m_summary.framesWithoutTracks << " without known-association tracks";
  s << "; " << m_summary.fps << " fps (median " << std::setprecision(2) << m_summary.medianFrameMs << " ms/frame)"
    << "; map " << m_summary.finalMapSize << " features; median matched " << std::setprecision(0)
    << m_summary.medianMatched;
  if (m_summary.ate)
  {
    s << std::setprecision(4) << "; ATE (Sim3) " << m_summary.ate->rmse;
    if (m_summary.ate->pathLength > 0)
      s << " = " << std::setprecision(2) << 100 * m_summary.ate->rmseOverPath << " % of path, "
        << 100 * m_summary.ate->rmseOverExtent << " % of extent";
    else
      s << " (the ground-truth camera did not move)";
    s << " (" << m_summary.ate->nPairs << " poses)";
  }
  if (m_summary.ateRefined && m_summary.ateRefined->pathLength > 0)
    s << std::setprecision(2) << "; refined " << 100 * m_summary.ateRefined->rmseOverPath << " % of path";
  if (!m_summary.endReason.empty()) s << "; ended: " << m_summary.endReason;
  s << "; outputs in " << m_args.outDir;
  std::cout << s.str() << std::endl;
  if (m_summary.framesProcessed == 0)
  {
    std::cerr << "imm-monoslam: error: no usable frame in the input (" << m_summary.framesRead << " read, "
              << m_summary.framesSkipped << " skipped"
              << (m_summary.skipReasons.empty() ? std::string() : "; first: " + m_summary.skipReasons[0]) << ")\n";
    return 1;
  }
  if (source->endedOnDamage())
  {
    // Every output up to the damage is written (above); the damage itself is an error of the input.
    std::cerr << "imm-monoslam: error: " << m_summary.endReason << " (outputs up to it written to " << m_args.outDir
              << ")\n";
    return 1;
  }
  return 0;
}
}  // namespace immslam::app
