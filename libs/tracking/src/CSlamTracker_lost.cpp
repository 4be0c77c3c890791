/* imm-monoslam — the SLAM tracker's lost tracking: the lost-frame state and relocalisation against
 * the map (relocalise.h: the map's templates at the image's corners, RANSAC PnP), whose pose the
 * filter takes (CImmSlamFilter::correctPose). */
#include <immslam/math/quaternion.h>
#include <immslam/tracking/CSlamTracker.h>
#include <immslam/tracking/relocalise.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace immslam::slam
{
namespace
{
/** Map points good enough for relocalisation: XYZ, or inverse depth known to 25 % (1 sigma). A point
 * whose depth is merely positive (depthKnown) may sit anywhere on a long stretch of its ray, and a PnP
 * from another viewpoint cannot use it. */
constexpr double kRelocMaxRelativeRhoStd = 0.25;
}  // namespace

bool CSlamTracker::wellLocalised(const TFeature& f) const
{
  if (f.kind == EFeatureKind::XYZ) return true;
  const double rho = m_filter.fusedMean()[f.offset + 5];
  const double var = m_filter.fusedCovarianceBlock(f.offset + 5, 1)(0, 0);
  return rho > 0 && std::sqrt(std::max(var, 0.0)) < kRelocMaxRelativeRhoStd * rho;
}

bool CSlamTracker::tryRelocalise(const cv::Mat& grey)
{
  // Templates as first seen and as they looked from the last tracked pose (the camera is often found
  // near it, but not after a long or fast excursion).
  const auto& cam = m_filter.camera();
  std::vector<TRelocPoint> pts;
  for (const auto& f : m_filter.features())
  {
    const frontend::CFeaturePatch* patch = patchOf(f.id);
    if (!patch || !wellLocalised(f)) continue;
    const Vec3 p_W = m_filter.featurePosition(f);
    Mat2 A = Mat2::Identity();
    if (m_opts.warp_patches)
    {
      Vec3 n = f.r0 - p_W;
      if (n.norm() > 0) n.normalize();
      A = frontend::patchWarp(cam, f.r0, f.q0, m_lastTrackedR, m_lastTrackedQ, p_W, n);
    }
    pts.push_back(TRelocPoint{f.id, p_W, {patch->originalTemplate(), patch->predictTemplate(A)}});
  }
  TRelocaliseParams p;
  // Corners a little weaker than new features need: a feature seen from elsewhere loses contrast.
  p.fastThreshold = std::max(5, m_opts.fast_threshold / 2);
  p.minNcc = m_opts.min_ncc;
  p.minInliers = m_opts.relocalise_min_inliers;
  p.reprojectionPx = std::max(2.0, 3.0 * m_filter.sigmaPixel());
  p.validMask = m_detectMask;
  const TRelocalisation res = relocalise(grey, cam, pts, p);
  m_sawNoMap = res.nCorners >= 4 * p.minInliers && !res.ok;
  m_report.nRelocMatches = res.nCorrespondences;
  m_report.nRelocInliers = static_cast<int>(res.inlierIds.size());
  if (!res.ok) return false;
  // The found pose's uncertainty, generously: 3 sigma of a pixel in rotation, and in translation the
  // same angle at 3x the inliers' median depth (the depth of a PnP pose from a shallow map is its
  // weakest direction). The next update, with these same features, refines it.
  const double focal = m_filter.focal();
  const double sTheta = 3.0 * m_filter.sigmaPixel() / focal;
  const double sT = 3.0 * sTheta * res.medianDepth;
  // Velocities: unknown after a long loss (zero, initial priors). Lost for a frame or two in a fast
  // motion, the camera keeps moving as it did: the displacement from the last tracked pose, per frame,
  // with its own size as a further 30 % std (else the next frame, predicted at rest, is lost again).
  Mat6 V = Mat6::Zero();
  const double sv = m_opts.init_linear_velocity_std_px / focal, sw = m_opts.init_angular_velocity_std_px / focal;
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
  m_filter.correctPose(res.r_CW, res.q_CW, sT, sTheta, vel, V);
  return true;
}

void CSlamTracker::updateLostState()
{
  if (!m_opts.relocalise) return;
  // Lost: (almost) nothing matched, or a fifth or less of what was searched (normal frames never come
  // close: 0-2 such frames in the 1000 of monoslam_testseq and the 99 of visp_rbt), with a map that
  // relocalisation could find.
  const bool failed = m_report.nMatched < 3 || (m_report.nPredicted >= 10 && m_report.nMatched < 0.2 * m_report.nPredicted);
  const auto& features = m_filter.features();
  const auto enoughLocalised = [&] {
    int known = 0;
    for (const auto& f : features)
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
    for (int k = 0; k < static_cast<int>(features.size()); ++k)
      m_filter.featureRecord(k).nPredicted = m_filter.featureRecord(k).nMatched = 0;
  }
  if (!lost)
  {
    m_sinceTracked = 0;
    m_lastTrackedR = m_filter.cameraPosition();
    m_lastTrackedQ = m_filter.cameraOrientation();
  }
  if (!lost || !relocalising()) return;
  // A frame-level failure (blackout, blur, a motion no model predicted) says nothing about the
  // features themselves: their failed searches do not count towards the deletion rule.
  std::unordered_map<std::int64_t, int> index;
  for (int k = 0; k < static_cast<int>(features.size()); ++k) index[features[k].id] = k;
  for (const auto& rec : m_report.searches)
  {
    if (rec.status == TSearchRecord::EStatus::LowInnovationInlier || rec.status == TSearchRecord::EStatus::RescuedInlier)
      continue;
    const auto it = index.find(rec.id);
    if (it != index.end() && features[it->second].nPredicted > 0) m_filter.featureRecord(it->second).nPredicted--;
  }
}
}  // namespace immslam::slam
