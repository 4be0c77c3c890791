/* imm-monoslam — the IMM SLAM filter's map operations (new features, deletion, inverse depth -> XYZ,
 * paper Sec. IV-2) on every mode, and its fused results in the world frame. */
#include <immslam/features/inverse_depth.h>
#include <immslam/math/parallel.h>
#include <immslam/math/quaternion.h>
#include <immslam/slam/CImmSlamFilter.h>
#include <immslam/slam/measurement.h>
#include <immslam/slam/state_ops.h>

#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace immslam::slam
{
std::vector<std::int64_t> CImmSlamFilter::addFeatures(const std::vector<TNewFeature>& fresh)
{
  std::vector<std::int64_t> ids;
  if (fresh.empty()) return ids;
  std::vector<TNewRay> rays;
  int off = static_cast<int>(m_imm->mode(0).x.size());
  for (const auto& nf : fresh)
  {
    TNewRay ray;
    ray.b_C = m_cam->unproject(nf.uv, &ray.J_b_uv).unitVector();
    ray.rho = nf.rho;
    ray.sigmaRho = nf.sigmaRho;
    ray.sigmaPixel = m_sigmaPixel;
    rays.push_back(ray);
    TFeature f;
    f.id = nf.id;
    f.kind = EFeatureKind::InverseDepth;
    f.offset = off;
    off += 6;
    f.r0 = m_rWC;
    f.q0 = m_qWC;
    f.tInit = m_lastTimestamp;
    f.frameInit = m_frame;
    f.lastSeenFrame = m_frame;
    ids.push_back(f.id);
    m_features.push_back(std::move(f));
  }
  // Undelayed initialisation in every mode with that mode's own camera estimate.
  m_pool->parallelFor(0, m_imm->numModels(), [&](int i) { appendInverseDepthFeatures(m_imm->mode(i), rays); });
  refreshFused();
  return ids;
}

void CImmSlamFilter::removeFeatures(const std::vector<std::int64_t>& ids)
{
  const std::unordered_set<std::int64_t> del(ids.begin(), ids.end());
  std::vector<TReparamSegment> segs{TReparamSegment{0, headDim(), true, {}, {}}};
  std::vector<TFeature> kept;
  int off = headDim();
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

void CImmSlamFilter::clonePose(const std::function<bool(std::int64_t)>& keep, int maxClones)
{
  if (maxClones <= 0) return;
  // Slots no longer wanted are free; the new clone takes one in place (O(n) per mode), a new slot
  // while there are fewer than maxClones (the state grows once), else the oldest clone's.
  int slot = -1;
  for (int c = 0; c < numClones(); ++c)
  {
    auto& f = m_cloneFrames[static_cast<std::size_t>(c)];
    if (f >= 0 && !keep(f)) f = -1;
    if (f < 0 && slot < 0) slot = c;
  }
  if (slot < 0 && numClones() >= maxClones)
    slot = static_cast<int>(std::min_element(m_cloneFrames.begin(), m_cloneFrames.end()) - m_cloneFrames.begin());
  if (slot < 0)
  {
    // A new slot at the end of the clone blocks, before the features.
    const int head = headDim();
    const int n = static_cast<int>(m_imm->mode(0).x.size());
    TReparamSegment clone{0, 1, false, VecX::Zero(kPoseCloneDim), MatX::Zero(kPoseCloneDim, 1)};
    clone.newValue[3] = 1.0;
    std::vector<TReparamSegment> segs{TReparamSegment{0, head, true, {}, {}}, clone};
    if (n > head) segs.push_back(TReparamSegment{head, n - head, true, {}, {}});
    m_pool->parallelFor(0, m_imm->numModels(), [&](int i) {
      materialize(i);
      reparametrize(m_imm->mode(i), segs);
    });
    for (auto& f : m_features) f.offset += kPoseCloneDim;
    m_cloneFrames.push_back(m_frame);
  }
  else
  {
    // T_C_C = identity, exactly: no covariance, no correlation.
    const int off = poseCloneOffset(slot);
    m_pool->parallelFor(0, m_imm->numModels(), [&](int i) {
      materialize(i);
      auto& g = m_imm->mode(i);
      g.x.segment<kPoseCloneDim>(off) << 0, 0, 0, 1, 0, 0, 0;
      g.P.middleRows<kPoseCloneDim>(off).setZero();
      g.P.middleCols<kPoseCloneDim>(off).setZero();
    });
    m_cloneFrames[static_cast<std::size_t>(slot)] = m_frame;
  }
  refreshFused();
}

bool CImmSlamFilter::relativePose(std::int64_t frame, Vec3& t, Vec4& q, Mat6& cov) const
{
  const auto it = std::find(m_cloneFrames.begin(), m_cloneFrames.end(), frame);
  if (frame < 0 || it == m_cloneFrames.end()) return false;
  const int off = poseCloneOffset(static_cast<int>(it - m_cloneFrames.begin()));
  invertPoseClone(m_xFused.segment<3>(off), m_xFused.segment<4>(off + 3), fusedCovarianceBlock(off, kPoseCloneDim), t,
                  q, cov);
  return true;
}

double CImmSlamFilter::linearityIndex(const TFeature& f) const
{
  const double varRho = fusedCovarianceBlock(f.offset + 5, 1)(0, 0);
  // Camera-centred: the current camera is the origin.
  return features::linearityIndex(m_xFused.segment<6>(f.offset), std::sqrt(std::max(varRho, 0.0)), Vec3::Zero());
}

void CImmSlamFilter::reparametrizeMap(const std::vector<char>& drop, const std::vector<char>& convert)
{
  // One re-parametrization per mode: copies of unchanged runs, converted blocks, dropped ones omitted.
  m_pool->parallelFor(0, m_imm->numModels(), [&](int i) {
    auto& g = m_imm->mode(i);
    std::vector<TReparamSegment> segs;
    int runStart = 0, runLen = headDim();
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
  int off = headDim();
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
  refreshFused();
}

void CImmSlamFilter::refreshFused()
{
  if (m_imm->numModels() == 1)
    m_xFused = m_imm->mode(0).x;
  else
    m_imm->combine(m_imm->probabilities(), m_xFused, nullptr);
  // The fused quaternion is a weighted mean of unit quaternions: renormalize the mean.
  m_xFused.segment<4>(3).normalize();
  updateWorldPose();
}

void CImmSlamFilter::updateWorldPose()
{
  worldPoseFromState(m_xFused, m_rWC, m_qWC);
  m_qWC.normalize();
}

Eigen::Matrix<double, 7, 7> CImmSlamFilter::cameraPoseCovariance() const
{
  Vec3 r;
  Vec4 q;
  Eigen::Matrix<double, 7, 7> J;
  worldPoseFromState(m_xFused, r, q, &J);
  return J * fusedCovarianceBlock(0, 7) * J.transpose();
}

MatX CImmSlamFilter::fusedCovarianceBlock(int offset, int len) const
{
  if (m_imm->numModels() == 1) return m_imm->mode(0).P.block(offset, offset, len, len);
  return m_imm->combinedBlock(m_imm->probabilities(), m_xFused, offset, len);
}

MatX CImmSlamFilter::fusedCovariance() const
{
  if (m_imm->numModels() == 1) return m_imm->mode(0).P;
  VecX x;
  MatX P;
  m_imm->combine(m_imm->probabilities(), x, &P, m_pool.get());
  return P;
}

VecX CImmSlamFilter::modelProbabilities() const { return m_imm->probabilities(); }

bool CImmSlamFilter::depthKnown(const TFeature& f) const
{
  if (f.kind == EFeatureKind::XYZ) return true;
  const double rho = m_xFused[f.offset + 5];
  const double var = fusedCovarianceBlock(f.offset + 5, 1)(0, 0);
  return rho - 1.96 * std::sqrt(std::max(var, 0.0)) > 0;
}

Vec3 CImmSlamFilter::featurePosition(const TFeature& f) const
{
  return math::quatRotate(m_qWC, featurePointInCamera(m_xFused, f)) + m_rWC;
}

TFeatureWorldEstimate CImmSlamFilter::featureWorldEstimate(const TFeature& f) const
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
  // W is the camera frame after the motion dq = q_CW, t = -R_CW r_WC (features::transformInverseDepth,
  // which owns the Jacobian of the angles' rotation); rho is unchanged.
  const Vec4 qCW = math::quatConjugate(m_qWC);
  Mat6 J_y;
  const Vec6 yW = features::transformInverseDepth(y, qCW, -math::quatRotate(qCW, m_rWC), &J_y);
  e.anchor_W = yW.head<3>();
  e.theta = yW[3];
  e.phi = yW[4];
  e.rho = y[5];
  const Mat3 T = J_y.bottomRightCorner<3, 3>();
  e.cov_tpr = T * Pff.bottomRightCorner<3, 3>() * T.transpose();
  return e;
}
}  // namespace immslam::slam
