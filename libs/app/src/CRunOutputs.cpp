/* imm-monoslam — the writers of a run (see CRunOutputs.h) and those that write files and figures
 * (output_sinks.h; the visual ones are in visual_sinks.cpp). */
#include "CRunOutputs.h"

#include "output_sinks.h"

#include <immslam/camera/mrpt_camera.h>
#include <immslam/refine/bundle_adjust.h>
#include <immslam/eval/statistics.h>
#include <immslam/io/CCsvWriter.h>
#include <immslam/io/CLiveCameraSource.h>
#include <immslam/sim/CSyntheticSource.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

namespace immslam::app::detail
{
namespace
{
/** [output] refine_trajectory: bundle adjustment of the run's own matches from `start` (the smoothed
 * trajectory, or the filter's), written to trajectory_refined.txt, with its ATE when the input has
 * ground truth. */
void refineTrajectory(const std::vector<eval::TSearchRow>& rows, const core::TTrajectory& start,
                      const COutputFiles& out, const camera::CCameraModel& cam,
                      const std::optional<core::TTrajectory>& gt, TRunSummary& summary,
                      mrpt::system::COutputLogger& log)
{
  const auto t0 = std::chrono::steady_clock::now();
  try
  {
    refine::TBundleProblem prob = refine::makeBundleProblem(rows, start, cam, 1e-6, 8, 6);
    const double before = refine::reprojectionStats(prob).rmsPx;
    const refine::TBundleResult r = refine::bundleAdjust(prob);
    const double after = refine::reprojectionStats(prob).rmsPx;
    // Every frame: those the adjustment left out (fewer than 6 of its features measured: the filter
    // lost its map, a fast turn) interpolated between the refined poses around them.
    const core::TTrajectory refined = core::completeTrajectory(prob.poses, start);
    core::writeTumTrajectory(refined, out.path("trajectory_refined.txt"));
    summary.refineSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::ostringstream m;
    m << std::fixed << std::setprecision(3) << "trajectory_refined.txt: " << prob.poses.size() << " of " << refined.size() << " poses, "
      << prob.points.size() << " features, " << prob.obs.size() << " matches; reprojection RMS " << before << " -> "
      << after << " px in " << r.iterations << " iterations, " << std::setprecision(2) << summary.refineSeconds
      << " s";
    if (r.components > 1) m << "; " << r.components << " unrelated blocks (the run started new maps), each in its own frame";
    log.logStr(mrpt::system::LVL_INFO, m.str());
    if (gt && prob.poses.size() >= 3) summary.ateRefined = eval::computeAte(refined, *gt, eval::EAlignment::Sim3, 0.01);
  }
  catch (const std::exception& e)
  {
    log.logStr(mrpt::system::LVL_WARN, std::string("no refined trajectory: ") + e.what());
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
}  // namespace

CFilesSink::CFilesSink(const TRunContext& ctx, const TRunInputs& in, const system::CMonoSlamSystem& sys)
    : m_files(ctx.args.outDir, sys.slam(), sys.shadowFilter() != nullptr, in.out.search_log, in.out.relative_pose_lag > 0)
{
}

void CFilesSink::onFrame(const TFrameResult& r) { m_files.addFrame(r.report, r.slam); }

void CFilesSink::onEnd(const slam::CMonoSlamIMM& slam, TRunSummary&) { m_files.writeMap(slam); }

CStatisticsSink::CStatisticsSink(const TRunContext& ctx, const TRunInputs& in, const core::TTrajectory& trajectory)
    : m_ctx(ctx), m_in(in), m_trajectory(trajectory)
{
}

void CStatisticsSink::onFrame(const TFrameResult& r)
{
  m_frameMs.push_back(r.report.totalMs);
  m_matched.push_back(r.report.slam->nMatched);
}

void CStatisticsSink::onEnd(const slam::CMonoSlamIMM& slam, TRunSummary& summary)
{
  mrpt::system::COutputLogger& log = m_ctx.log;
  if (summary.framesWithoutMask > 0)
    log.logStr(mrpt::system::LVL_WARN, "[input] exclusion_masks: " + std::to_string(summary.framesWithoutMask) +
                                           " frame(s) had no mask for their timestamp and excluded nothing");
  if (summary.framesWithoutTracks > 0)
    log.logStr(mrpt::system::LVL_WARN, "[input] known_association: " + std::to_string(summary.framesWithoutTracks) +
                                           " frame(s) had no track at their timestamp (prediction only)");
  summary.finalMapSize = static_cast<int>(slam.features().size());
  if (!m_frameMs.empty())
  {
    summary.medianFrameMs = eval::median(m_frameMs);
    summary.meanFrameMs = eval::mean(m_frameMs);
    summary.medianMatched = eval::median(m_matched);
    summary.fps = 1000.0 / std::max(summary.meanFrameMs, 1e-9);
  }
  if (const auto gt = m_in.source->groundTruth(); gt && m_trajectory.size() >= 3)
  {
    try
    {
      summary.ate = eval::computeAte(m_trajectory, *gt, eval::EAlignment::Sim3, 0.01);
    }
    catch (const std::exception& e)
    {
      log.logStr(mrpt::system::LVL_WARN, std::string("no ATE: ") + e.what());
    }
  }
}

namespace
{
/** True motion labels of a rendered dataset folder (motion_labels.txt: "timestamp label"), if any. */
std::map<long long, std::string> readMotionLabels(const std::string& folder)
{
  std::map<long long, std::string> out;
  std::ifstream f(std::filesystem::path(folder) / "motion_labels.txt");
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
}  // namespace

CTruthSeriesSink::CTruthSeriesSink(const TRunContext& ctx, const TRunInputs& in)
    : m_ctx(ctx),
      m_in(in),
      m_synthetic(dynamic_cast<const sim::CSyntheticSource*>(in.source.get())),
      m_folderLabels(in.inputPath.empty() ? std::map<long long, std::string>() : readMotionLabels(in.inputPath))
{
}

void CTruthSeriesSink::onFrame(const TFrameResult& r)
{
  const double t = r.slam.lastReport().timestamp;
  if (m_synthetic)
    m_labels.emplace_back(t, sim::toString(m_synthetic->label(r.frame.index)));
  else if (const auto it = m_folderLabels.find(std::llround(r.frame.timestamp * 1e6)); it != m_folderLabels.end())
    m_labels.emplace_back(t, it->second);
}

void CTruthSeriesSink::onEnd(const slam::CMonoSlamIMM&, TRunSummary& summary)
{
  const std::filesystem::path dir(m_ctx.args.outDir);
  if (!m_labels.empty())
  {
    io::CCsvWriter f((dir / "motion_labels.csv").string(), {"timestamp", "label"});
    for (const auto& [t, label] : m_labels) f.addRow(t, label);
  }
  if (summary.ate)
  {
    io::CCsvWriter f((dir / "ate.csv").string(), {"timestamp", "position_error"});
    for (const auto& pe : summary.ate->errors) f.addRow(pe.tEst, pe.position);
  }
}

CRefineSink::CRefineSink(const TRunContext& ctx, const TRunInputs& in, const COutputFiles& files,
                         const CSmoothingSink* smoothing)
    : m_ctx(ctx), m_in(in), m_files(files), m_smoothing(smoothing)
{
}

void CRefineSink::onFrame(const TFrameResult& r)
{
  // The low-innovation and rescued inliers of the frame.
  const slam::TFrameReport& rep = *r.report.slam;
  for (const auto& sr : rep.searches)
    if (sr.status == slam::TSearchRecord::EStatus::LowInnovationInlier ||
        sr.status == slam::TSearchRecord::EStatus::RescuedInlier)
    {
      eval::TSearchRow row;
      row.timestamp = rep.timestamp;
      row.featureId = sr.id;
      row.h = sr.h;
      row.S = sr.S;
      row.found = true;
      row.z = sr.z;
      row.score = sr.score;
      row.status = sr.status == slam::TSearchRecord::EStatus::RescuedInlier ? eval::ESearchStatus::Rescued
                                                                            : eval::ESearchStatus::Inlier;
      m_rows.push_back(row);
    }
  // The shadow filter's past matches of the features that turned out static (as the smoother).
  m_stamps.push_back(rep.timestamp);
  for (const auto& hm : r.heldBack)
  {
    eval::TSearchRow row;
    row.timestamp = m_stamps[hm.frame];
    row.featureId = hm.id;
    row.found = true;
    row.z = hm.uv;
    row.status = eval::ESearchStatus::Inlier;
    m_rows.push_back(row);
  }
}

void CRefineSink::onEnd(const slam::CMonoSlamIMM&, TRunSummary& summary)
{
  // The smoothed trajectory, where there is one, is the better start: the adjustment reaches the same
  // minimum from either when the filter is good, and from it where the filter lost its map.
  const bool smoothed = m_smoothing && m_smoothing->trajectory().size() == m_files.trajectory().size();
  refineTrajectory(m_rows, smoothed ? m_smoothing->trajectory() : m_files.trajectory(), m_files, *m_in.cam,
                   m_in.source->groundTruth(), summary, m_ctx.log);
}

CSmoothingSink::CSmoothingSink(const TRunInputs& in, const COutputFiles& files, mrpt::system::COutputLogger& log)
    : m_in(in),
      m_files(files),
      m_log(log),
      m_smoothing(*in.cam, dynamic_cast<const io::CLiveCameraSource*>(in.source.get()) != nullptr)
{
}

void CSmoothingSink::onFrame(const TFrameResult& r)
{
  m_smoothing.addFrame(r.report, r.slam, m_files.trajectory().back(), r.heldBack);
}

void CSmoothingSink::onEnd(const slam::CMonoSlamIMM&, TRunSummary& summary)
{
  m_smoothing.finish(m_files.path("trajectory_smoothed.txt"), m_in.source->groundTruth(), summary, m_log);
}

CProgressSink::CProgressSink(const TRunSummary& summary, std::size_t total)
    : m_summary(summary), m_total(total), m_start(Clock::now()), m_last(m_start)
{
}

void CProgressSink::onFrame(const TFrameResult& r)
{
  if (std::chrono::duration<double>(Clock::now() - m_last).count() <= 0.2) return;
  m_last = Clock::now();
  const double el = std::chrono::duration<double>(m_last - m_start).count();
  const double fps = (r.processed + 1) / std::max(el, 1e-9);
  const VecX mu = r.slam.modelProbabilities();
  int best = 0;
  mu.maxCoeff(&best);
  const std::size_t read = m_summary.framesRead;
  std::fprintf(stderr, "\rframe %zu%s  %.1f fps  map %d  matched %d  %s %.2f", read,
               m_total ? ("/" + std::to_string(m_total)).c_str() : "", fps, r.report.slam->nMap,
               r.report.slam->nMatched, r.slam.models()[best].name.c_str(), mu[best]);
  if (m_total > read) std::fprintf(stderr, "  ETA %s", formatSeconds((m_total - read) / std::max(fps, 1e-9)).c_str());
  std::fprintf(stderr, "   ");
}

void CProgressSink::onEnd(const slam::CMonoSlamIMM&, TRunSummary&) { std::fprintf(stderr, "\n"); }

CRunOutputs::CRunOutputs(const TRunContext& ctx, const TRunInputs& in, const system::CMonoSlamSystem& sys,
                         const TRunSummary& summary, bool calibrationGuessed)
{
  if (!ctx.args.quiet && isatty(fileno(stderr)))
    m_sinks.push_back(std::make_unique<CProgressSink>(summary, in.source->sizeHint()));
  auto files = std::make_unique<CFilesSink>(ctx, in, sys);
  m_files = &files->files();
  m_sinks.push_back(std::move(files));
  if (calibrationGuessed) camera::saveCalibFile(*in.cam, m_files->path("calib_guessed.txt"));
  const core::TTrajectory& trajectory = m_files->trajectory();
  m_sinks.push_back(std::make_unique<CStatisticsSink>(ctx, in, trajectory));
  m_sinks.push_back(std::make_unique<CTruthSeriesSink>(ctx, in));  // after the statistics: reads the ATE
  const CSmoothingSink* smoothing = nullptr;
  if (in.out.smooth_trajectory)
  {
    auto sink = std::make_unique<CSmoothingSink>(in, *m_files, ctx.log);
    smoothing = sink.get();
    m_sinks.push_back(std::move(sink));
  }
  // After the smoothing: it starts from the smoothed trajectory (the sinks end in this order).
  if (in.out.refine_trajectory) m_sinks.push_back(std::make_unique<CRefineSink>(ctx, in, *m_files, smoothing));
  if (in.out.overlays || in.out.overlay_video) m_sinks.push_back(std::make_unique<COverlaySink>(ctx.args.outDir, in.out));
  if (CLiveView::available(ctx.args.noGui))
    m_sinks.push_back(std::make_unique<CLiveViewSink>(in.out, trajectory, smoothing));
  // After the smoothing: the final scene draws the whole smoothed trajectory.
  if (in.out.scene || in.out.scene_every_n > 0)
    m_sinks.push_back(std::make_unique<CSceneSink>(ctx, in, trajectory, smoothing));
}

CRunOutputs::~CRunOutputs() = default;

const COutputFiles& CRunOutputs::files() const { return *m_files; }

std::vector<IFrameSink*> CRunOutputs::sinks()
{
  std::vector<IFrameSink*> out;
  for (const auto& s : m_sinks) out.push_back(s.get());
  return out;
}
}  // namespace immslam::app::detail
