/* imm-monoslam — the SLAM tracker's association: active search in the fused ellipses (eqs. 13-14)
 * with warped templates, the same gate for given matches, and the detection of new corners. */
#include <immslam/math/chi2.h>
#include <immslam/math/parallel.h>
#include <immslam/math/quaternion.h>
#include <immslam/tracking/CSlamTracker.h>
#include <immslam/slam/measurement.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <functional>
#include <unordered_map>

namespace immslam::slam
{
namespace
{
/** One feature's search: its fused prediction and what the search found. */
struct TSearchJob
{
  int k = -1;
  const frontend::CFeaturePatch* patch = nullptr;
  Vec2 h;
  Mat2F Jf;
  Mat2 S;
  frontend::TSearchResult res;
  bool outside = false;  ///< found outside the 95 % ellipse (the search for a feature that started moving)
};

/** Image motion (px, 1 sigma) added to the search of a feature found in the previous frame and lost
 * now: its 95 % region reaches about 10 px, 3-4 frames of an object that started to move at 2-3 px
 * per frame (the handover needs 3 rejections in a row). */
constexpr double kStartedMovingSigmaPx = 4.0;
/** Correlation a match of that search needs (at least [slam] min_ncc). */
constexpr double kStartedMovingMinNcc = 0.9;

frontend::TSearchParams searchParams(const CSlamTracker::TOptions& o)
{
  frontend::TSearchParams sp;
  sp.gateChi2 = math::chi2Quantile(o.search_probability, 2);
  sp.minScore = o.min_ncc;
  sp.maxHalfExtentPx = o.max_search_half_extent_px;
  return sp;
}

/** Searches again, in parallel, the jobs for which again(j) holds, in their ellipse S k2 + grow. */
void searchAgain(math::CThreadPool& pool, const cv::Mat& grey, const std::vector<cv::Mat>& templates, double k2,
                 const Mat2& grow, const frontend::TSearchParams& sp, std::vector<TSearchJob>& jobs,
                 const std::function<bool(const TSearchJob&)>& again)
{
  pool.parallelFor(0, static_cast<int>(jobs.size()), [&](int idx) {
    TSearchJob& j = jobs[idx];
    if (again(j)) j.res = frontend::searchInEllipse(grey, templates[idx], j.h, j.S * k2 + grow, sp);
  });
}

/** The second searches of the features not found in their ellipse; returns true when it was the
 * expanded search of a motion no model predicted. */
bool searchMissed(math::CThreadPool& pool, const cv::Mat& grey, const std::vector<cv::Mat>& templates,
                  const frontend::TSearchParams& sp, const CSlamTracker::TOptions& o, const std::vector<TFeature>& features,
                  std::int64_t frame, std::vector<TSearchJob>& jobs)
{
  // Expanded search: when the motion was not predicted (an acceleration beyond every model), most
  // matches fall outside their ellipses together. The features not found are searched again in
  // ellipses grown by expand_search_factor; 1-point RANSAC then decides with the filter's own S
  // (a hypothesis from one such match must be supported by the others).
  int nFound = 0;
  for (const auto& j : jobs) nFound += j.res.found ? 1 : 0;
  const double k2 = o.expand_search_factor * o.expand_search_factor;
  if (o.expand_search_factor > 1 && !jobs.empty() && nFound < o.expand_below_fraction * jobs.size())
  {
    searchAgain(pool, grey, templates, k2, Mat2::Zero(), sp, jobs, [](const TSearchJob& j) { return !j.res.found; });
    return true;
  }
  // A feature found in the previous frame and not in its ellipse now may have started to move (a
  // mapped object that leaves; a well-mapped feature's ellipse is 1-2 px across): it is searched
  // again in its ellipse grown by expand_search_factor and by kStartedMovingSigmaPx, so that 1-point
  // RANSAC sees where it went; rejected frame after frame, it is handed over (doc/shadow.md).
  if (o.expand_search_factor > 1)
  {
    // A wider region holds more look-alikes: the match must be closer (an occluded static feature
    // must not be taken elsewhere and handed over).
    frontend::TSearchParams spMoved = sp;
    spMoved.minScore = std::max(sp.minScore, kStartedMovingMinNcc);
    const std::int64_t previous = frame - 1;
    const auto lostNow = [&](const TSearchJob& j) { return !j.res.found && features[j.k].lastFoundFrame == previous; };
    for (auto& j : jobs) j.outside = lostNow(j);  // searched again: outside its ellipse if found
    searchAgain(pool, grey, templates, k2, kStartedMovingSigmaPx * kStartedMovingSigmaPx * Mat2::Identity(), spMoved,
                jobs, [](const TSearchJob& j) { return j.outside; });
    for (auto& j : jobs)
    {
      const Vec2 nu = j.res.uv - j.h;
      j.outside = j.outside && j.res.found && nu.dot(j.S.ldlt().solve(nu)) > sp.gateChi2;
    }
  }
  return false;
}
}  // namespace

const frontend::CFeaturePatch* CSlamTracker::patchOf(std::int64_t id) const
{
  const auto it = m_patches.find(id);
  return it == m_patches.end() ? nullptr : &it->second;
}

std::vector<TCandidate> CSlamTracker::searchFeatures(const cv::Mat& grey)
{
  Vec3 r_WC;
  Vec4 q_WC;
  worldPoseFromState(m_filter.predictedMean(), r_WC, q_WC);
  q_WC.normalize();
  const frontend::TSearchParams sp = searchParams(m_opts);
  const auto& cam = m_filter.camera();
  const auto& features = m_filter.features();

  // Predict every feature (cheap), then search the visible ones (the image work) in parallel.
  std::vector<TSearchJob> jobs;
  jobs.reserve(features.size());
  for (int k = 0; k < static_cast<int>(features.size()); ++k)
  {
    TSearchJob j;
    j.k = k;
    j.patch = patchOf(features[k].id);
    if (!j.patch) continue;
    if (!m_filter.predictedMeasurement(features[k], j.h, &j.Jf)) continue;
    if (!cam.isInImage(j.h, m_opts.patch_half_size + 1)) continue;
    jobs.push_back(j);
  }
  std::vector<cv::Mat> templates(jobs.size());
  auto& pool = m_filter.threadPool();
  pool.parallelFor(0, static_cast<int>(jobs.size()), [&](int idx) {
    TSearchJob& j = jobs[idx];
    const TFeature& f = features[j.k];
    // S_i = H_i P H_i^T + R with the fused P (eq. 14): only the feature's own block is needed.
    j.S = m_filter.predictedInnovationCovariance(f, j.Jf);
    Mat2 A = Mat2::Identity();
    if (m_opts.warp_patches)
    {
      const Vec3 p = math::quatRotate(q_WC, featurePointInCamera(m_filter.predictedMean(), f)) + r_WC;
      Vec3 n = f.r0 - p;
      if (n.norm() > 0) n.normalize();
      A = frontend::patchWarp(cam, f.r0, f.q0, r_WC, q_WC, p, n);
    }
    templates[idx] = j.patch->predictTemplate(A);
    j.res = frontend::searchInEllipse(grey, templates[idx], j.h, j.S, sp);
  });
  m_report.expandedSearch = searchMissed(pool, grey, templates, sp, m_opts, features, m_filter.frame(), jobs);

  std::vector<TCandidate> cands;
  double areaSum = 0;
  for (auto& j : jobs)
  {
    // Excluded pixels (setExclusionMask): a match there is not the feature's.
    if (j.res.found && frontend::maskedAt(m_excluded, j.res.uv)) j.res.found = false;
    areaSum += frontend::ellipseArea(j.S, sp.gateChi2);
    recordSearch(j.k, j.h, j.Jf, j.S, j.res.found, j.res.uv, j.res.score, cands);
    if (j.res.found && j.outside) cands.back().outsideGate = true;
  }
  m_report.meanSearchAreaPx2 = jobs.empty() ? 0.0 : areaSum / jobs.size();
  m_report.nFound = static_cast<int>(cands.size());
  return cands;
}

void CSlamTracker::recordSearch(int k, const Vec2& h, const Mat2F& Jf, const Mat2& S, bool found, const Vec2& z,
                                double score, std::vector<TCandidate>& cands)
{
  TFeature& f = m_filter.featureRecord(k);
  f.nPredicted++;
  f.lastSeenFrame = m_filter.frame();
  ++m_report.nPredicted;
  TSearchRecord rec;
  rec.id = f.id;
  rec.h = h;
  rec.S = S;
  rec.found = found;
  rec.z = z;
  rec.score = score;
  m_report.searches.push_back(rec);
  if (found) f.lastFoundFrame = m_filter.frame();
  if (found) cands.push_back(TCandidate{k, z, h, Jf, S});
}

std::vector<TCandidate> CSlamTracker::gateMeasurements(const std::vector<std::pair<std::int64_t, Vec2>>& z)
{
  // The active search with the matches given: every feature predicted in the image is searched, and
  // its measurement is found if it lies in the feature's search ellipse (eqs. 13-14, fused).
  std::unordered_map<std::int64_t, Vec2> measured;
  for (const auto& [id, uv] : z)
    if (uv.allFinite()) measured.emplace(id, uv);
  const double gate = math::chi2Quantile(m_opts.search_probability, 2);
  std::vector<TCandidate> cands;
  double areaSum = 0;
  const auto& features = m_filter.features();
  for (int k = 0; k < static_cast<int>(features.size()); ++k)
  {
    const TFeature& f = features[k];
    Vec2 h;
    Mat2F Jf;
    if (!m_filter.predictedMeasurement(f, h, &Jf) || !m_filter.camera().isInImage(h)) continue;
    const Mat2 S = m_filter.predictedInnovationCovariance(f, Jf);
    areaSum += frontend::ellipseArea(S, gate);
    const auto it = measured.find(f.id);
    if (it == measured.end())
    {
      recordSearch(k, h, Jf, S, false, Vec2::Zero(), -1, cands);
      continue;
    }
    const Vec2 nu = it->second - h;
    recordSearch(k, h, Jf, S, nu.dot(S.ldlt().solve(nu)) <= gate, it->second, 1, cands);
  }
  m_report.meanSearchAreaPx2 = m_report.nPredicted ? areaSum / m_report.nPredicted : 0.0;
  m_report.nFound = static_cast<int>(cands.size());
  return cands;
}

std::vector<TCandidate> CSlamTracker::takeMeasurements(const std::vector<std::pair<std::int64_t, Vec2>>& z)
{
  const auto& features = m_filter.features();
  std::unordered_map<std::int64_t, int> index;
  for (int k = 0; k < static_cast<int>(features.size()); ++k) index[features[k].id] = k;
  std::vector<TCandidate> cands;
  for (const auto& [id, uv] : z)
  {
    const auto it = index.find(id);
    if (it == index.end()) continue;
    TCandidate c;
    c.feature = it->second;
    c.z = uv;
    cands.push_back(c);
    TFeature& f = m_filter.featureRecord(c.feature);
    f.nPredicted++;
    f.lastSeenFrame = m_filter.frame();
  }
  m_report.nPredicted = m_report.nFound = static_cast<int>(cands.size());
  return cands;
}

std::vector<frontend::TCorner> CSlamTracker::findNewFeatureCandidates(const cv::Mat& grey, int maxNew,
                                                                      const std::vector<Vec2>& alsoOccupied,
                                                                      int gridScale) const
{
  std::vector<Vec2> occupied = alsoOccupied;
  // (A map given up is not where its features are predicted: their cells are free.)
  if (!mapGivenUp())
  {
    for (const auto& rec : m_report.searches) occupied.push_back(rec.found ? rec.z : rec.h);
    // Features not searched this frame but predicted inside the image still occupy their cell.
    const auto& cam = m_filter.camera();
    for (const auto& f : m_filter.features())
    {
      Vec2 uv;
      if (f.lastSeenFrame != m_filter.frame() && predictMeasurement(cam, m_filter.fusedMean(), f, uv) &&
          cam.isInImage(uv))
        occupied.push_back(uv);
    }
  }
  frontend::TDetectorParams p;
  p.fastThreshold = m_opts.fast_threshold;
  p.gridCols = m_opts.grid_cols * gridScale;
  p.gridRows = m_opts.grid_rows * gridScale;
  p.minDistancePx = m_opts.min_corner_distance_px;
  p.borderPx = detectionBorderPx();
  p.minShiTomasi = m_opts.min_shi_tomasi;
  p.validMask = m_detectMask;
  return frontend::detectInEmptyCells(grey, occupied, maxNew, p);
}
}  // namespace immslam::slam

