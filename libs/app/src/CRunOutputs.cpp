/* imm-monoslam — the outputs of a run (see CRunOutputs.h). */
#include "CRunOutputs.h"

#include <immslam/refine/bundle_adjust.h>
#include <immslam/eval/statistics.h>
#include <immslam/sim/CSyntheticSource.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

namespace immslam::app::detail
{
namespace fs = std::filesystem;

namespace
{
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

/** [output] refine_trajectory: bundle adjustment of the run's own matches (the filter's trajectory as
 * the start), written to trajectory_refined.txt, with its ATE when the input has ground truth. */
void refineTrajectory(const std::vector<eval::TSearchRow>& rows, const COutputFiles& out,
                      const camera::CCameraModel& cam, const std::optional<core::TTrajectory>& gt,
                      TRunSummary& summary, mrpt::system::COutputLogger& log)
{
  const auto t0 = std::chrono::steady_clock::now();
  try
  {
    refine::TBundleProblem prob = refine::makeBundleProblem(rows, out.trajectory(), cam, 1e-6, 8, 6);
    const double before = refine::reprojectionStats(prob).rmsPx;
    const refine::TBundleResult r = refine::bundleAdjust(prob);
    const double after = refine::reprojectionStats(prob).rmsPx;
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

CRunOutputs::CRunOutputs(const TRunContext& ctx, const TRunInputs& in, const system::CMonoSlamSystem& sys)
    : m_ctx(ctx),
      m_in(in),
      m_files(ctx.args.outDir, sys.slam(), sys.shadowFilter() != nullptr, in.out.search_log),
      m_visuals(ctx.args.outDir, in.out, sys.slam(), CLiveView::available(ctx.args.noGui)),
      m_synthetic(dynamic_cast<const sim::CSyntheticSource*>(in.source.get())),
      m_folderLabels(in.inputPath.empty() ? std::map<long long, std::string>() : readMotionLabels(in.inputPath))
{
}

void CRunOutputs::addFrame(std::size_t processed, const io::TFrame& frame, const system::TSystemFrame& fr,
                           const slam::CMonoSlamIMM& slam)
{
  m_files.addFrame(fr, slam);
  m_visuals.onFrame(processed, frame.colour.empty() ? frame.grey : frame.colour, fr, slam, m_files.trajectory());
  if (m_in.out.plots) addLabel(frame);  // the true labels are only drawn in the probability plot
  if (m_in.out.refine_trajectory) addRefineRows(fr);
  if (m_in.out.smooth_trajectory)
  {
    if (!m_smoothing) m_smoothing = std::make_unique<CTrajectorySmoothing>(*m_in.cam);  // the camera is settled now
    m_smoothing->addFrame(fr, m_files.trajectory().back());
  }
  m_frameMs.push_back(fr.totalMs);
  m_matched.push_back(fr.slam->nMatched);
}

void CRunOutputs::addLabel(const io::TFrame& frame)
{
  if (m_synthetic)
    m_labels.push_back(sim::toString(m_synthetic->label(frame.index)));
  else if (const auto it = m_folderLabels.find(std::llround(frame.timestamp * 1e6)); it != m_folderLabels.end())
    m_labels.push_back(it->second);
}

void CRunOutputs::addRefineRows(const system::TSystemFrame& fr)
{
  for (const auto& sr : fr.slam->searches)
    if (sr.status == slam::TSearchRecord::EStatus::LowInnovationInlier ||
        sr.status == slam::TSearchRecord::EStatus::RescuedInlier)
    {
      eval::TSearchRow row;
      row.timestamp = fr.slam->timestamp;
      row.featureId = sr.id;
      row.h = sr.h;
      row.S = sr.S;
      row.found = true;
      row.z = sr.z;
      row.score = sr.score;
      row.status = sr.status == slam::TSearchRecord::EStatus::RescuedInlier ? eval::ESearchStatus::Rescued
                                                                            : eval::ESearchStatus::Inlier;
      m_refineRows.push_back(row);
    }
}

void CRunOutputs::finish(const slam::CMonoSlamIMM& slam, TRunSummary& summary)
{
  mrpt::system::COutputLogger& log = m_ctx.log;
  if (summary.framesWithoutMask > 0)
    log.logStr(mrpt::system::LVL_WARN, "[input] exclusion_masks: " + std::to_string(summary.framesWithoutMask) +
                                           " frame(s) had no mask for their timestamp and excluded nothing");
  if (summary.framesWithoutTracks > 0)
    log.logStr(mrpt::system::LVL_WARN, "[input] known_association: " + std::to_string(summary.framesWithoutTracks) +
                                           " frame(s) had no track at their timestamp (prediction only)");
  m_files.writeMap(slam);
  summary.finalMapSize = static_cast<int>(slam.features().size());
  if (!m_frameMs.empty())
  {
    summary.medianFrameMs = eval::median(m_frameMs);
    summary.meanFrameMs = eval::mean(m_frameMs);
    summary.medianMatched = eval::median(m_matched);
    summary.fps = 1000.0 / std::max(summary.meanFrameMs, 1e-9);
  }
  if (const auto gt = m_in.source->groundTruth(); gt && m_files.trajectory().size() >= 3)
  {
    try
    {
      summary.ate = eval::computeAte(m_files.trajectory(), *gt, eval::EAlignment::Sim3, 0.01);
    }
    catch (const std::exception& e)
    {
      log.logStr(mrpt::system::LVL_WARN, std::string("no ATE: ") + e.what());
    }
  }
  if (m_in.out.refine_trajectory)
    refineTrajectory(m_refineRows, m_files, *m_in.cam, m_in.source->groundTruth(), summary, log);
  if (m_smoothing)
    m_smoothing->finish(m_files.path("trajectory_smoothed.txt"), m_in.source->groundTruth(), summary, log);
  std::vector<std::string> warnings;
  m_visuals.finish(slam, m_files.trajectory(), m_in.source->groundTruth(), summary.ate, m_labels, warnings);
  for (const auto& w : warnings) log.logStr(mrpt::system::LVL_WARN, w);
}
}  // namespace immslam::app::detail
