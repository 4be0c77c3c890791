/* imm-monoslam — map management of the IMM SLAM bank: new features, deletion, ID -> XYZ
 * conversion (paper Sec. IV-2), and the per-frame driver. */
#include <immslam/features/inverse_depth.h>
#include <immslam/frontend/frontend.h>
#include <immslam/math/chi2.h>
#include <immslam/math/gaussian.h>
#include <immslam/math/quaternion.h>
#include <immslam/math/parallel.h>
#include <immslam/slam/CMonoSlamIMM.h>
#include <immslam/slam/measurement.h>
#include <immslam/slam/relocalise.h>
#include <immslam/slam/robocentric_prediction.h>
#include <immslam/slam/state_ops.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

namespace immslam::slam
{
namespace
{
/** Map points good enough for relocalisation: XYZ, or inverse depth known to 25 % (1 sigma). A point
 * whose depth is merely positive (depthKnown) may sit anywhere on a long stretch of its ray, and a PnP
 * from another viewpoint cannot use it. */
constexpr double kRelocMaxRelativeRhoStd = 0.25;
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}
}  // namespace

void CMonoSlamIMM::beginFrame(double timestamp)
{
  ++m_frame;
  m_report = TFrameReport();
  m_report.timestamp = timestamp;
  m_report.frame = m_frame;
  m_report.sigmaPixel = m_sigmaPixel;
}

void CMonoSlamIMM::endFrame(Clock::time_point t0)
{
  refreshFused();
  m_report.nMap = static_cast<int>(m_features.size());
  m_report.nDepthKnown = 0;
  for (const auto& f : m_features) m_report.nDepthKnown += depthKnown(f) ? 1 : 0;
  m_report.timeMs = msSince(t0);
}

void CMonoSlamIMM::predictStep(double timestamp)
{
  m_report.dtFrames = frameDt(timestamp);
  m_sinceTracked += m_report.dtFrames;
  const auto t = Clock::now();
  predict(m_report.dtFrames);
  m_report.tPredictMs = msSince(t);
  m_report.lostFrames = m_lostFrames;
  m_sawNoMap = false;
}

void CMonoSlamIMM::gateMeasurements(const std::vector<std::pair<std::int64_t, Vec2>>& z, std::vector<TCandidate>& cands)
{
  // The active search with the matches given: every feature predicted in the image is searched, and
  // its measurement is found if it lies in the feature's search ellipse (eqs. 13-14, fused).
  std::unordered_map<std::int64_t, Vec2> measured;
  for (const auto& [id, uv] : z)
    if (uv.allFinite()) measured.emplace(id, uv);
  const double gate = math::chi2Quantile(m_opts.search_probability, 2);
  double areaSum = 0;
  for (int k = 0; k < static_cast<int>(m_features.size()); ++k)
  {
    TFeature& f = m_features[k];
    Vec2 h;
    Mat2F Jf;
    if (!predictMeasurement(*m_cam, m_xPred, f, h, &Jf) || !m_cam->isInImage(h)) continue;
    const Mat2 S = innovationCovariance(predictedCovBlock(f.offset, f.dim()), Jf, m_sigmaPixel);
    f.nPredicted++;
    f.lastSeenFrame = m_frame;
    areaSum += frontend::ellipseArea(S, gate);
    ++m_report.nPredicted;
    TSearchRecord rec;
    rec.id = f.id;
    rec.h = h;
    rec.S = S;
    const auto it = measured.find(f.id);
    if (it != measured.end())
    {
      const Vec2 nu = it->second - h;
      rec.found = nu.dot(S.ldlt().solve(nu)) <= gate;
      rec.z = it->second;
      rec.score = 1;
    }
    m_report.searches.push_back(rec);
    if (rec.found) cands.push_back(TCandidate{k, rec.z, h, Jf, S});
  }
  m_report.meanSearchAreaPx2 = m_report.nPredicted ? areaSum / m_report.nPredicted : 0.0;
  m_report.nFound = static_cast<int>(cands.size());
}

const TFrameReport& CMonoSlamIMM::processMeasurements(double timestamp,
                                                       const std::vector<std::pair<std::int64_t, Vec2>>& z, bool robust)
{
  const auto t0 = Clock::now();
  beginFrame(timestamp);
  if (m_frame == 0)
    m_lastTimestamp = timestamp;
  else if (robust)
  {
    predictStep(timestamp);
    const auto t = Clock::now();
    std::vector<TCandidate> cands;
    gateMeasurements(z, cands);
    m_report.tSearchMs = msSince(t);
    associateAndUpdate(cands);
  }
  else
  {
    predictStep(timestamp);
    std::unordered_map<std::int64_t, int> index;
    for (int k = 0; k < static_cast<int>(m_features.size()); ++k) index[m_features[k].id] = k;
    std::vector<TCandidate> cands;
    for (const auto& [id, uv] : z)
    {
      const auto it = index.find(id);
      if (it == index.end()) continue;
      TCandidate c;
      c.feature = it->second;
      c.z = uv;
      cands.push_back(c);
      m_features[c.feature].nPredicted++;
      m_features[c.feature].lastSeenFrame = m_frame;
    }
    m_report.nPredicted = m_report.nFound = static_cast<int>(cands.size());
    std::vector<int> all(cands.size());
    std::iota(all.begin(), all.end(), 0);
    VecX logLik = VecX::Zero(m_imm->numModels());
    updateBank(cands, all, logLik);
    if (m_imm->numModels() > 1) m_imm->updateProbabilities(logLik);
    settleDormantModes();
    refreshFused();
    const int minPred = m_opts.delete_min_predictions;
    m_opts.delete_min_predictions = std::numeric_limits<int>::max();  // no deletion: known association
    manageMap();
    m_opts.delete_min_predictions = minPred;
  }
  endFrame(t0);
  return m_report;
}

void CMonoSlamIMM::associateAndUpdate(std::vector<TCandidate>& cands)
{
  auto t = Clock::now();
  const std::vector<int> low = m_ransac.lowInnovationInliers(
      *m_cam, m_xPred, [this](int off, int len) { return predictedCovColumns(off, len); }, m_features, cands, m_rng,
      &m_report.nHypotheses);
  m_report.tRansacMs = msSince(t);

  t = Clock::now();
  const int r = m_imm->numModels();
  VecX logLik = VecX::Zero(r);
  updateBank(cands, low, logLik);
  m_report.nLowInnovation = m_report.nMatched;
  std::vector<char> used(cands.size(), 0);
  for (int c : low) used[c] = 1;
  // Weights for the rescue test: mu_{k|k-1} L^(1) normalized in log space.
  m_rescueWeights = VecX::Ones(r);
  if (r > 1)
  {
    VecX a(r);
    for (int i = 0; i < r; ++i) a[i] = std::log(std::max(m_imm->predictedProbabilities()[i], 1e-300)) + logLik[i];
    const double lse = math::logSumExp(a);
    m_rescueWeights = std::isfinite(lse) ? VecX((a.array() - lse).exp()) : m_imm->predictedProbabilities();
    // Dormant modes are still at their prediction: the rescue test uses the updated ones.
    for (int i = 0; i < r; ++i)
      if (m_dormant[i]) m_rescueWeights[i] = 0;
    if (m_rescueWeights.sum() > 0) m_rescueWeights /= m_rescueWeights.sum();
  }
  const std::vector<int> high = rescue(cands, used);
  updateBank(cands, high, logLik);
  m_report.nRescued = m_report.nMatched - m_report.nLowInnovation;
  if (r > 1) m_imm->updateProbabilities(logLik);
  settleDormantModes();
  m_report.nRejected = m_report.nFound - m_report.nMatched;
  for (int c : low) used[c] = 1;
  // Record the status of each search.
  {
    std::vector<char> isHigh(cands.size(), 0);
    for (int c : high) isHigh[c] = 1;
    std::unordered_map<std::int64_t, int> candOf;
    for (int c = 0; c < static_cast<int>(cands.size()); ++c) candOf[m_features[cands[c].feature].id] = c;
    for (auto& rec : m_report.searches)
    {
      if (!rec.found) continue;
      const int c = candOf[rec.id];
      rec.status = used[c] ? TSearchRecord::EStatus::LowInnovationInlier
                           : isHigh[c] ? TSearchRecord::EStatus::RescuedInlier : TSearchRecord::EStatus::Rejected;
      // Track record of outlier rejections (a feature that starts moving is rejected frame after frame).
      TFeature& f = m_features[cands[c].feature];
      f.rejectedInRow = rec.status == TSearchRecord::EStatus::Rejected ? f.rejectedInRow + 1 : 0;
    }
  }
  m_report.tUpdateMs = msSince(t);

  t = Clock::now();
  refreshFused();
  {
    std::vector<int> inliers = low;
    inliers.insert(inliers.end(), high.begin(), high.end());
    estimateMeasurementNoise(cands, inliers);
  }
  updateLostState();
  manageMap();
  m_report.tMapMs = msSince(t);
}

const TFrameReport& CMonoSlamIMM::processFrame(double timestamp, const cv::Mat& grey)
{
  if (grey.type() != CV_8UC1 || grey.cols != m_cam->width() || grey.rows != m_cam->height())
  {
    std::ostringstream s;
    s << "image of " << grey.cols << "x" << grey.rows << " (type " << grey.type() << ") does not match the "
      << m_cam->width() << "x" << m_cam->height() << " 8-bit grey camera";
    throw std::runtime_error(s.str());
  }
  const auto t0 = Clock::now();
  beginFrame(timestamp);

  if (m_frame == 0)
  {
    // Start on the fly, no known pattern: corners of the first image at the inverse-depth prior.
    m_lastTimestamp = timestamp;
    m_xPred = m_xFused;
    const auto corners = findNewFeatureCandidates(grey, m_opts.initial_features);
    std::vector<Vec2> uv;
    for (const auto& c : corners) uv.push_back(c.uv);
    addFeaturesAt(grey, uv);
  }
  else
  {
    predictStep(timestamp);
    // Lost in the previous frame, or a gap in the frames over which the motion models' prediction
    // cannot be trusted: look for the map in the whole image first.
    if (relocalising() || (m_opts.relocalise && m_opts.relocalise_after_gap > 0 &&
                           m_report.dtFrames > m_opts.relocalise_after_gap))
    {
      const auto t = Clock::now();
      m_report.relocalised = tryRelocalise(grey);
      m_report.tRelocMs = msSince(t);
    }

    const auto t = Clock::now();
    std::vector<TCandidate> cands;
    searchFeatures(grey, cands);
    m_report.tSearchMs = msSince(t);

    associateAndUpdate(cands);
  }
  endFrame(t0);
  return m_report;
}

bool CMonoSlamIMM::tryRelocalise(const cv::Mat& grey)
{
  // Templates as first seen and as they looked from the last tracked pose (the camera is often found
  // near it, but not after a long or fast excursion).
  std::vector<TRelocPoint> pts;
  for (const auto& f : m_features)
  {
    if (!f.patch.valid() || !wellLocalised(f)) continue;
    const Vec3 p_W = featurePosition(f);
    Mat2 A = Mat2::Identity();
    if (m_opts.warp_patches)
    {
      Vec3 n = f.r0 - p_W;
      if (n.norm() > 0) n.normalize();
      A = frontend::patchWarp(*m_cam, f.r0, f.q0, m_lastTrackedR, m_lastTrackedQ, p_W, n);
    }
    pts.push_back(TRelocPoint{f.id, p_W, {f.patch.originalTemplate(), f.patch.predictTemplate(A)}});
  }
  TRelocaliseParams p;
  // Corners a little weaker than new features need: a feature seen from elsewhere loses contrast.
  p.fastThreshold = std::max(5, m_opts.fast_threshold / 2);
  p.minNcc = m_opts.min_ncc;
  p.minInliers = m_opts.relocalise_min_inliers;
  p.reprojectionPx = std::max(2.0, 3.0 * m_sigmaPixel);
  p.validMask = m_detectMask;
  const TRelocalisation res = relocalise(grey, *m_cam, pts, p);
  m_sawNoMap = res.nCorners >= 4 * p.minInliers && !res.ok;
  m_report.nRelocMatches = res.nCorrespondences;
  m_report.nRelocInliers = static_cast<int>(res.inlierIds.size());
  if (!res.ok) return false;
  // The found pose's uncertainty, generously: 3 sigma of a pixel in rotation, and in translation the
  // same angle at 3x the inliers' median depth (the depth of a PnP pose from a shallow map is its
  // weakest direction). The next update, with these same features, refines it.
  const double sTheta = 3.0 * m_sigmaPixel / m_focal;
  const double sT = 3.0 * sTheta * res.medianDepth;
  // Velocities: unknown after a long loss (zero, initial priors). Lost for a frame or two in a fast
  // motion, the camera keeps moving as it did: the displacement from the last tracked pose, per frame,
  // with its own size as a further 30 % std (else the next frame, predicted at rest, is lost again).
  Mat6 V = Mat6::Zero();
  const double sv = m_opts.init_linear_velocity_std_px / m_focal, sw = m_opts.init_angular_velocity_std_px / m_focal;
  Vec6 vel = Vec6::Zero();
  const double elapsed = m_sinceTracked;  // frame periods since the last tracked frame
  if (elapsed > 0 && elapsed <= 3)
  {
    const Vec4 qCW = res.q_CW;
    const Vec4 qWC = math::quatConjugate(qCW);
    const Vec3 rWC = -math::quatRotate(qWC, res.r_CW);
    vel.head<3>() = math::quatRotate(qCW, Vec3(rWC - m_lastTrackedR)) / elapsed;
    vel.tail<3>() = math::quatToRotationVector(math::quatMultiply(math::quatConjugate(m_lastTrackedQ), qWC)) / elapsed;
  }
  V.topLeftCorner<3, 3>() = Mat3::Identity() * (sv * sv + 0.09 * vel.head<3>().squaredNorm());
  V.bottomRightCorner<3, 3>() = Mat3::Identity() * (sw * sw + 0.09 * vel.tail<3>().squaredNorm());
  const int r = m_imm->numModels();
  m_pool->parallelFor(0, r, [&](int i) {
    materialize(i);
    applyPoseCorrection(m_imm->mode(i), m_features, res.r_CW, res.q_CW, sT, sTheta, vel, V, m_scratch[i]);
  });
  if (r == 1)
    m_xPred = m_imm->mode(0).x;
  else
    m_imm->combine(m_imm->predictedProbabilities(), m_xPred, nullptr);
  return true;
}

void CMonoSlamIMM::updateLostState()
{
  if (!m_opts.relocalise) return;
  // Lost: (almost) nothing matched, or a fifth or less of what was searched (normal frames never come
  // close: 0-2 such frames in the 1000 of monoslam_testseq and the 99 of visp_rbt), with a map that
  // relocalisation could find.
  const bool failed = m_report.nMatched < 3 || (m_report.nPredicted >= 10 && m_report.nMatched < 0.2 * m_report.nPredicted);
  const auto enoughLocalised = [this] {
    int known = 0;
    for (const auto& f : m_features)
      if (wellLocalised(f) && ++known >= m_opts.relocalise_min_inliers) return true;
    return false;
  };
  const bool lost = failed && enoughLocalised();
  const bool wasHolding = relocalising();
  m_lostFrames = lost ? m_lostFrames + 1 : 0;
  m_noMapFrames = lost && m_sawNoMap ? m_noMapFrames + 1 : 0;
  if (wasHolding && mapGivenUp())
  {
    // The map is given up: its features must prove themselves again. With their records cleared, the
    // deletion rule removes those not found in the next delete_min_predictions searches (a lifetime
    // of matches would otherwise keep a feature the camera has left for hundreds of frames), and
    // keeps those the camera finds again.
    for (auto& f : m_features) f.nPredicted = f.nMatched = 0;
  }
  if (!lost)
  {
    m_sinceTracked = 0;
    m_lastTrackedR = m_rWC;
    m_lastTrackedQ = m_qWC;
  }
  if (!lost || !relocalising()) return;
  // A frame-level failure (blackout, blur, a motion no model predicted) says nothing about the
  // features themselves: their failed searches do not count towards the deletion rule.
  std::unordered_map<std::int64_t, int> index;
  for (int k = 0; k < static_cast<int>(m_features.size()); ++k) index[m_features[k].id] = k;
  for (const auto& rec : m_report.searches)
  {
    if (rec.status == TSearchRecord::EStatus::LowInnovationInlier || rec.status == TSearchRecord::EStatus::RescuedInlier)
      continue;
    const auto it = index.find(rec.id);
    if (it != index.end() && m_features[it->second].nPredicted > 0) m_features[it->second].nPredicted--;
  }
}

void CMonoSlamIMM::refreshFused()
{
  if (m_imm->numModels() == 1)
    m_xFused = m_imm->mode(0).x;
  else
    m_imm->combine(m_imm->probabilities(), m_xFused, nullptr);
  // The fused quaternion is a weighted mean of unit quaternions: renormalize the mean.
  m_xFused.segment<4>(3).normalize();
  updateWorldPose();
}

void CMonoSlamIMM::manageMap()
{
  // 1. Deletion (MonoSLAM rule, paper ref. [6]): searched often, matched rarely.
  std::vector<char> drop(m_features.size(), 0);
  for (std::size_t k = 0; k < m_features.size(); ++k)
  {
    const auto& f = m_features[k];
    if (f.nPredicted >= m_opts.delete_min_predictions &&
        f.nMatched < m_opts.delete_min_match_ratio * f.nPredicted)
      drop[k] = 1;
  }
  // 2. Inverse depth -> XYZ when the linearity index is small (paper ref. [3]).
  std::vector<char> convert(m_features.size(), 0);
  if (m_opts.convert_to_xyz)
  {
    const Vec3 r = Vec3::Zero();  // camera-centred: the current camera is the origin
    const VecX& mu = m_imm->probabilities();
    for (std::size_t k = 0; k < m_features.size(); ++k)
    {
      const auto& f = m_features[k];
      if (drop[k] || f.kind != EFeatureKind::InverseDepth) continue;
      const double varRho = m_imm->numModels() == 1 ? m_imm->mode(0).P(f.offset + 5, f.offset + 5)
                                                    : m_imm->combinedBlock(mu, m_xFused, f.offset + 5, 1)(0, 0);
      const double L = features::linearityIndex(m_xFused.segment<6>(f.offset), std::sqrt(std::max(varRho, 0.0)), r);
      if (L < m_opts.linearity_threshold) convert[k] = 1;
    }
  }
  m_report.nDeleted = static_cast<int>(std::count(drop.begin(), drop.end(), 1));
  m_report.nConverted = static_cast<int>(std::count(convert.begin(), convert.end(), 1));
  if (!m_report.nDeleted && !m_report.nConverted) return;

  // One re-parametrization per mode: copies of unchanged runs, converted blocks, dropped ones omitted.
  const int r = m_imm->numModels();
  m_pool->parallelFor(0, r, [&](int i) {
    auto& g = m_imm->mode(i);
    std::vector<TReparamSegment> segs;
    int runStart = 0, runLen = motion::kCamDim;
    auto flush = [&] {
      if (runLen > 0) segs.push_back(TReparamSegment{runStart, runLen, true, {}, {}});
      runLen = 0;
    };
    for (std::size_t k = 0; k < m_features.size(); ++k)
    {
      const auto& f = m_features[k];
      if (!drop[k] && !convert[k])
      {
        if (runLen == 0) runStart = f.offset;
        runLen += f.dim();
        continue;
      }
      flush();
      if (convert[k])
      {
        features::Mat36 J;
        TReparamSegment s{f.offset, 6, false, {}, {}};
        s.newValue = features::inverseDepthToPoint(g.x.segment<6>(f.offset), &J);
        s.J = J;
        segs.push_back(std::move(s));
      }
    }
    flush();
    reparametrize(g, segs);
  });
  std::vector<TFeature> kept;
  kept.reserve(m_features.size());
  int off = motion::kCamDim;
  for (std::size_t k = 0; k < m_features.size(); ++k)
  {
    if (drop[k]) continue;
    TFeature f = std::move(m_features[k]);
    if (convert[k]) f.kind = EFeatureKind::XYZ;
    f.offset = off;
    off += f.dim();
    kept.push_back(std::move(f));
  }
  m_features = std::move(kept);
}

void CMonoSlamIMM::removeFeatures(const std::vector<std::int64_t>& ids)
{
  const std::unordered_set<std::int64_t> del(ids.begin(), ids.end());
  std::vector<TReparamSegment> segs{TReparamSegment{0, motion::kCamDim, true, {}, {}}};
  std::vector<TFeature> kept;
  int off = motion::kCamDim;
  for (auto& f : m_features)
  {
    if (del.count(f.id)) continue;
    segs.push_back(TReparamSegment{f.offset, f.dim(), true, {}, {}});
    f.offset = off;
    off += f.dim();
    kept.push_back(std::move(f));
  }
  if (kept.size() == m_features.size()) return;
  m_pool->parallelFor(0, m_imm->numModels(), [&](int i) { reparametrize(m_imm->mode(i), segs); });
  m_features = std::move(kept);
  refreshFused();
}

std::vector<frontend::TCorner> CMonoSlamIMM::findNewFeatureCandidates(const cv::Mat& grey, int maxNew,
                                                                      const std::vector<Vec2>& alsoOccupied,
                                                                      int gridScale) const
{
  std::vector<Vec2> occupied = alsoOccupied;
  // (A map given up is not where its features are predicted: their cells are free.)
  if (!mapGivenUp())
  {
    for (const auto& rec : m_report.searches) occupied.push_back(rec.found ? rec.z : rec.h);
    // Features not searched this frame but predicted inside the image still occupy their cell.
    for (const auto& f : m_features)
    {
      Vec2 uv;
      if (f.lastSeenFrame != m_frame && predictMeasurement(*m_cam, m_xFused, f, uv) && m_cam->isInImage(uv))
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

std::vector<std::int64_t> CMonoSlamIMM::addFeaturesAt(const cv::Mat& grey, const std::vector<Vec2>& uvs,
                                                      const std::vector<std::pair<double, double>>& rhoPrior,
                                                      const std::vector<std::int64_t>& givenIds)
{
  std::vector<std::int64_t> ids(uvs.size(), -1);
  // Bounded map: evict the features unseen for longest (not visible now) to make room.
  const int room = m_opts.max_map_features - static_cast<int>(m_features.size());
  if (room < static_cast<int>(uvs.size()))
  {
    std::vector<std::pair<std::int64_t, std::int64_t>> byAge;  // (lastSeenFrame, id)
    for (const auto& f : m_features)
      if (f.lastSeenFrame < m_frame) byAge.emplace_back(f.lastSeenFrame, f.id);
    std::sort(byAge.begin(), byAge.end());
    std::vector<std::int64_t> evict;
    for (std::size_t i = 0; i < byAge.size() && static_cast<int>(evict.size()) < static_cast<int>(uvs.size()) - room; ++i)
      evict.push_back(byAge[i].second);
    removeFeatures(evict);
  }
  const int capacity = m_opts.max_map_features - static_cast<int>(m_features.size());

  std::vector<TNewRay> rays;
  std::vector<TFeature> fresh;
  for (std::size_t i = 0; i < uvs.size() && static_cast<int>(fresh.size()) < capacity; ++i)
  {
    TFeature f;
    if (!grey.empty() && !f.patch.extract(grey, uvs[i], m_opts.patch_half_size)) continue;
    TNewRay ray;
    ray.b_C = m_cam->unproject(uvs[i], &ray.J_b_uv).unitVector();
    ray.rho = i < rhoPrior.size() ? rhoPrior[i].first : m_opts.init_rho;
    ray.sigmaRho = i < rhoPrior.size() ? rhoPrior[i].second : m_opts.init_rho_std;
    ray.sigmaPixel = m_sigmaPixel;
    rays.push_back(ray);
    f.id = i < givenIds.size() ? givenIds[i] : m_nextId++;
    f.kind = EFeatureKind::InverseDepth;
    f.r0 = m_rWC;
    f.q0 = m_qWC;
    f.tInit = m_lastTimestamp;
    f.frameInit = m_frame;
    f.lastSeenFrame = m_frame;
    ids[i] = f.id;
    fresh.push_back(std::move(f));
  }
  if (rays.empty()) return ids;
  int off = static_cast<int>(m_imm->mode(0).x.size());
  for (auto& f : fresh)
  {
    f.offset = off;
    off += 6;
  }
  // Undelayed initialisation in every mode with that mode's own camera estimate.
  m_pool->parallelFor(0, m_imm->numModels(), [&](int i) { appendInverseDepthFeatures(m_imm->mode(i), rays); });
  for (auto& f : fresh) m_features.push_back(std::move(f));
  m_report.nAdded += static_cast<int>(rays.size());
  refreshFused();
  return ids;
}

Eigen::Matrix<double, 7, 7> CMonoSlamIMM::cameraPoseCovariance() const
{
  Vec3 r;
  Vec4 q;
  Eigen::Matrix<double, 7, 7> J;
  worldPoseFromState(m_xFused, r, q, &J);
  return J * fusedCovarianceBlock(0, 7) * J.transpose();
}

MatX CMonoSlamIMM::fusedCovarianceBlock(int offset, int len) const
{
  if (m_imm->numModels() == 1) return m_imm->mode(0).P.block(offset, offset, len, len);
  return m_imm->combinedBlock(m_imm->probabilities(), m_xFused, offset, len);
}

MatX CMonoSlamIMM::fusedCovariance() const
{
  if (m_imm->numModels() == 1) return m_imm->mode(0).P;
  VecX x;
  MatX P;
  m_imm->combine(m_imm->probabilities(), x, &P, m_pool.get());
  return P;
}

VecX CMonoSlamIMM::modelProbabilities() const { return m_imm->probabilities(); }

bool CMonoSlamIMM::depthKnown(const TFeature& f) const
{
  if (f.kind == EFeatureKind::XYZ) return true;
  const double rho = m_xFused[f.offset + 5];
  const double var = fusedCovarianceBlock(f.offset + 5, 1)(0, 0);
  return rho - 1.96 * std::sqrt(std::max(var, 0.0)) > 0;
}

bool CMonoSlamIMM::wellLocalised(const TFeature& f) const
{
  if (f.kind == EFeatureKind::XYZ) return true;
  const double rho = m_xFused[f.offset + 5];
  const double var = fusedCovarianceBlock(f.offset + 5, 1)(0, 0);
  return rho > 0 && std::sqrt(std::max(var, 0.0)) < kRelocMaxRelativeRhoStd * rho;
}

Vec3 CMonoSlamIMM::featurePosition(const TFeature& f) const
{
  return math::quatRotate(m_qWC, featurePointInCamera(m_xFused, f)) + m_rWC;
}
TFeatureWorldEstimate CMonoSlamIMM::featureWorldEstimate(const TFeature& f) const
{
  TFeatureWorldEstimate e;
  const Mat3 R_WC = math::quatToRotation(m_qWC);
  const MatX Pff = fusedCovarianceBlock(f.offset, f.dim());
  e.depthKnown = depthKnown(f);
  e.p_W = featurePosition(f);
  if (f.kind == EFeatureKind::XYZ)
  {
    e.cov_W = R_WC * Pff * R_WC.transpose();
    return e;
  }
  e.inverseDepth = true;
  const Vec6 y = m_xFused.segment<6>(f.offset);
  features::Mat36 J_p;
  Vec6 yc = y;
  yc[5] = std::max(yc[5], 1e-3);
  features::inverseDepthToPoint(yc, &J_p);
  e.cov_W = R_WC * J_p * Pff * J_p.transpose() * R_WC.transpose();
  e.anchor_W = R_WC * y.head<3>() + m_rWC;
  // Chain rule: (theta, phi)_W = angles(R_WC m(theta, phi)_C); rho unchanged.
  Mat32 J_m;
  const Vec3 mC = math::Bearing::DirectionFromAngles(y[3], y[4], &J_m);
  Mat23 J_ang;
  const Vec2 angW = math::Bearing::AzimuthElevation(R_WC * mC, &J_ang);
  e.theta = angW[0];
  e.phi = angW[1];
  e.rho = y[5];
  Mat3 T = Mat3::Zero();
  T.topLeftCorner<2, 2>() = J_ang * R_WC * J_m;
  T(2, 2) = 1;
  e.cov_tpr = T * Pff.bottomRightCorner<3, 3>() * T.transpose();
  return e;
}
}  // namespace immslam::slam
