/* imm-monoslam — the SLAM tracker's frame: associate (search in the image, or given matches), then
 * update (1-point RANSAC, the filter's updates, rescue, probabilities), then the map policy. */
#include <immslam/math/chi2.h>
#include <immslam/tracking/CSlamTracker.h>

#include <opencv2/core.hpp>
#include <algorithm>
#include <numeric>
#include <sstream>
#include <unordered_set>
#include <stdexcept>

namespace immslam::slam
{
namespace
{
double msSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/** The options, checked before anything is built from them. */
const CSlamTracker::TOptions& checked(const CSlamTracker::TOptions& opts, const camera::CCameraModel::Ptr& cam)
{
  if (!cam) throw std::invalid_argument("CMonoSlamIMM: no camera model");
  opts.validate("slam");
  return opts;
}
}  // namespace

CSlamTracker::CSlamTracker(const TOptions& opts, const TIMMBankOptions& bank, const COnePointRansac::TOptions& ransac,
                           camera::CCameraModel::Ptr cam)
    : m_opts(checked(opts, cam)),
      m_filter(opts.filterOptions(), bank, cam),
      m_ransac(ransac),
      m_rng(static_cast<unsigned>(opts.seed))
{
  m_lensMask = frontend::lensMask(*cam, detectionBorderPx());
  m_detectMask = m_lensMask;
}

void CSlamTracker::setExclusionMask(const cv::Mat& excluded)
{
  const auto& cam = m_filter.camera();
  if (!excluded.empty() &&
      (excluded.type() != CV_8UC1 || excluded.cols != cam.width() || excluded.rows != cam.height()))
    throw std::invalid_argument("CMonoSlamIMM::setExclusionMask: expected an empty mask or a CV_8UC1 image of " +
                                std::to_string(cam.width()) + "x" + std::to_string(cam.height()) + " pixels");
  m_excluded = frontend::growExclusion(excluded, m_opts.patch_half_size);
  m_detectMask = m_lensMask;
  if (m_excluded.empty()) return;
  m_detectMask = m_excluded == 0;
  if (!m_lensMask.empty()) cv::bitwise_and(m_detectMask, m_lensMask, m_detectMask);
}

void CSlamTracker::beginFrame(double timestamp)
{
  m_report = TFrameReport();
  m_report.timestamp = timestamp;
  m_report.frame = m_filter.beginFrame();
  m_report.sigmaPixel = m_filter.sigmaPixel();
  if (m_report.frame == 0) m_filter.start(timestamp);
}

void CSlamTracker::endFrame(Clock::time_point t0)
{
  const auto& features = m_filter.features();
  m_report.nMap = static_cast<int>(features.size());
  m_report.motionNoiseAngularPx = m_filter.loosestAngularNoisePx();
  m_report.shakePx = m_filter.shakePx();
  m_report.nDepthKnown = 0;
  for (const auto& f : features) m_report.nDepthKnown += m_filter.depthKnown(f) ? 1 : 0;
  if (m_relativeLag > 0)
  {
    // The motion since frame k - lag from its clone, then the clone of this frame in its place.
    const std::int64_t k = m_report.frame, j = k - m_relativeLag;
    for (const auto& [frame, time] : m_clonedTimes)
      if (frame == j && m_filter.relativePose(j, m_report.relT, m_report.relQ, m_report.relCov))
      {
        m_report.relFrom = j;
        m_report.relFromTimestamp = time;
      }
    const int lag = m_relativeLag;
    m_filter.clonePose([k, lag](std::int64_t f) { return k - f < lag; }, lag);
    m_clonedTimes.emplace_back(k, m_report.timestamp);
    if (static_cast<int>(m_clonedTimes.size()) > lag) m_clonedTimes.erase(m_clonedTimes.begin());
  }
  m_report.timeMs = msSince(t0);
}

void CSlamTracker::predictStep(double timestamp)
{
  const auto t = Clock::now();
  m_report.dtFrames = m_filter.predict(timestamp);
  m_report.tPredictMs = msSince(t);
  m_sinceTracked += m_report.dtFrames;
  m_report.lostFrames = m_lostFrames;
  m_sawNoMap = false;
}

const TFrameReport& CSlamTracker::processFrame(double timestamp, const cv::Mat& grey)
{
  const auto& cam = m_filter.camera();
  if (grey.type() != CV_8UC1 || grey.cols != cam.width() || grey.rows != cam.height())
  {
    std::ostringstream s;
    s << "image of " << grey.cols << "x" << grey.rows << " (type " << grey.type() << ") does not match the "
      << cam.width() << "x" << cam.height() << " 8-bit grey camera";
    throw std::runtime_error(s.str());
  }
  const auto t0 = Clock::now();
  beginFrame(timestamp);
  if (m_report.frame == 0)
    initialiseMap(grey);
  else
  {
    predictStep(timestamp);
    // Lost in the previous frame, or a gap in the frames over which the motion models' prediction
    // cannot be trusted: look for the map in the whole image first.
    if (relocalising() ||
        (m_opts.relocalise && m_opts.relocalise_after_gap > 0 && m_report.dtFrames > m_opts.relocalise_after_gap))
    {
      const auto t = Clock::now();
      m_report.relocalised = tryRelocalise(grey);
      m_report.tRelocMs = msSince(t);
    }
    const auto t = Clock::now();
    std::vector<TCandidate> cands = searchFeatures(grey);
    m_report.tSearchMs = msSince(t);
    associateAndUpdate(cands);
  }
  endFrame(t0);
  return m_report;
}

void CSlamTracker::initialiseMap(const cv::Mat& grey)
{
  // Start on the fly, no known pattern: corners of the first image at the inverse-depth prior.
  const auto corners = findNewFeatureCandidates(grey, m_opts.initial_features);
  std::vector<Vec2> uv;
  for (const auto& c : corners) uv.push_back(c.uv);
  addFeaturesAt(grey, uv);
}

const TFrameReport& CSlamTracker::processMeasurements(double timestamp,
                                                       const std::vector<std::pair<std::int64_t, Vec2>>& z, bool robust)
{
  const auto t0 = Clock::now();
  beginFrame(timestamp);
  if (m_report.frame > 0)
  {
    predictStep(timestamp);
    const auto t = Clock::now();
    std::vector<TCandidate> cands = robust ? gateMeasurements(z) : takeMeasurements(z);
    m_report.tSearchMs = msSince(t);
    if (robust)
      associateAndUpdate(cands);
    else
      updateWithAll(cands);
  }
  endFrame(t0);
  return m_report;
}

void CSlamTracker::updateWithAll(const std::vector<TCandidate>& cands)
{
  std::vector<int> all(cands.size());
  std::iota(all.begin(), all.end(), 0);
  m_report.nMatched += m_filter.update(cands, all);
  const auto act = m_filter.finishUpdate();
  m_report.nDormantModes = act.nDormant;
  m_report.nLazyModes = act.nLazy;
  manageMap(false);  // no deletion: known association
}

void CSlamTracker::associateAndUpdate(std::vector<TCandidate>& cands)
{
  auto t = Clock::now();
  // Matches outside their ellipse (a feature that may have started to move) take no part; the
  // candidates are copied only in the frames that have such a match.
  const bool anyOutside =
      std::any_of(cands.begin(), cands.end(), [](const TCandidate& c) { return c.outsideGate; });
  std::vector<TCandidate> gated;
  std::vector<int> gatedIndex;
  for (int c = 0; anyOutside && c < static_cast<int>(cands.size()); ++c)
  {
    if (cands[c].outsideGate) continue;
    gated.push_back(cands[c]);
    gatedIndex.push_back(c);
  }
  std::vector<int> low = m_ransac.lowInnovationInliers(
      m_filter.camera(), m_filter.predictedMean(), [this](int off, int len) { return m_filter.predictedCovColumns(off, len); },
      m_filter.features(), anyOutside ? gated : cands, m_rng, &m_report.nHypotheses);
  if (anyOutside)
    for (int& c : low) c = gatedIndex[c];
  m_report.tRansacMs = msSince(t);

  t = Clock::now();
  m_report.nMatched += m_filter.update(cands, low);
  m_report.nLowInnovation = m_report.nMatched;
  std::vector<char> used(cands.size(), 0), skip(cands.size(), 0);
  for (int c : low) used[c] = skip[c] = 1;
  for (int c = 0; c < static_cast<int>(cands.size()); ++c) skip[c] |= cands[c].outsideGate ? 1 : 0;
  const std::vector<int> high =
      m_filter.rescueGate(cands, skip, math::chi2Quantile(m_ransac.options().rescue_probability, 2));
  m_report.nMatched += m_filter.update(cands, high);
  m_report.nRescued = m_report.nMatched - m_report.nLowInnovation;
  const auto act = m_filter.finishUpdate();
  m_report.nDormantModes = act.nDormant;
  m_report.nLazyModes = act.nLazy;
  m_report.nRejected = m_report.nFound - m_report.nMatched;
  recordStatuses(cands, used, high);
  m_report.tUpdateMs = msSince(t);

  t = Clock::now();
  {
    std::vector<int> inliers = low;
    inliers.insert(inliers.end(), high.begin(), high.end());
    m_filter.learnShake(cands, inliers);
    m_filter.adaptMeasurementNoise(cands, inliers);
  }
  updateLostState();
  manageMap(true);
  m_report.tMapMs = msSince(t);
}

void CSlamTracker::recordStatuses(const std::vector<TCandidate>& cands, const std::vector<char>& used,
                                  const std::vector<int>& high)
{
  std::vector<char> isHigh(cands.size(), 0);
  for (int c : high) isHigh[c] = 1;
  std::unordered_map<std::int64_t, int> candOf;
  const auto& features = m_filter.features();
  for (int c = 0; c < static_cast<int>(cands.size()); ++c) candOf[features[cands[c].feature].id] = c;
  for (auto& rec : m_report.searches)
  {
    if (!rec.found) continue;
    const int c = candOf[rec.id];
    rec.status = used[c] ? TSearchRecord::EStatus::LowInnovationInlier
                         : isHigh[c] ? TSearchRecord::EStatus::RescuedInlier : TSearchRecord::EStatus::Rejected;
    // Track record of outlier rejections (a feature that starts moving is rejected frame after frame).
    TFeature& f = m_filter.featureRecord(cands[c].feature);
    f.rejectedInRow = rec.status == TSearchRecord::EStatus::Rejected ? f.rejectedInRow + 1 : 0;
    if (rec.status != TSearchRecord::EStatus::Rejected)
    {
      f.tLastInlier = m_report.timestamp;
      f.uvLastInlier = rec.z;
    }
  }
}
}  // namespace immslam::slam
