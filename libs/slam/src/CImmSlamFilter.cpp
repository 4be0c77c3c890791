/* imm-monoslam — the IMM SLAM filter: construction, time, mixing and mode-matched prediction, the
 * fused prediction (paper Fig. 2 step 1, eqs. 10-11) and the lazy modes' predicted covariance blocks.
 * Camera-centred state: x = (r_CW, q_CW, v, w, features in the current camera frame). */
#include <immslam/math/parallel.h>
#include <immslam/slam/CImmSlamFilter.h>
#include <immslam/slam/measurement.h>
#include <immslam/slam/robocentric_prediction.h>

// The filter knows no image (doc/architecture.md): its headers must not bring OpenCV in.
#ifdef CV_VERSION_MAJOR
#error "CImmSlamFilter.h or its includes pull in OpenCV"
#endif

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace immslam::slam
{
CImmSlamFilter::CImmSlamFilter(const TOptions& opts, const TIMMBankOptions& bank, camera::CCameraModel::Ptr cam)
    : m_opts(opts), m_cam(std::move(cam))
{
  if (!m_cam) throw std::invalid_argument("CImmSlamFilter: no camera model");
  m_models = bank.parseModels();
  const int r = static_cast<int>(m_models.size());
  m_imm = std::make_unique<bayes::CIMMEstimator>(bank.transitionMatrix(r), bank.priorProbabilities(r),
                                                 r > 1 ? bank.probability_floor : 0.0);
  m_pool = std::make_unique<math::CThreadPool>(static_cast<unsigned>(m_opts.num_threads));
  m_scratch.resize(r);
  m_dormantBelow = r > 1 ? bank.dormant_below : 0.0;
  m_dormant.assign(r, 0);
  m_wasDormant.assign(r, 0);
  m_lazyPrediction = m_dormantBelow > 0 && bank.lazy_prediction;
  m_lazy.resize(r);
  m_factors.resize(r);
  m_focal = 0.5 * (m_cam->fx() + m_cam->fy());
  m_sigmaPixel = m_opts.sigma_pixel;
  const auto loosest = [&](motion::EMotionFamily family) {
    int best = -1;
    for (int i = 0; i < r; ++i)
      if (m_models[i].family == family && (best < 0 || m_models[i].sigmaAngularPx > m_models[best].sigmaAngularPx))
        best = i;
    return best;
  };
  m_motionNoise.general = loosest(motion::EMotionFamily::General);
  m_motionNoise.rotation = loosest(motion::EMotionFamily::Rotation);
  if (m_motionNoise.general >= 0)
  {
    const double own = m_models[m_motionNoise.general].sigmaAngularPx;
    m_motionNoise.angular2 = own * own;  // learning starts from the model's own noise
  }
  initialiseState();
}

namespace
{
/** A learned noise as it acts: raised only by what the learned variance exceeds half again the
 * model's own (a right model's estimate scatters about its variance: the model's noise stays where
 * the camera keeps to it), and at most to `maxFactor` times it. */
double raisedNoise(double own, double learned2, double maxFactor)
{
  return std::min(maxFactor * own, std::sqrt(std::max(own * own, learned2 - 0.5 * own * own)));
}
}  // namespace

motion::TMotionModel CImmSlamFilter::effectiveModel(int i) const
{
  motion::TMotionModel m = m_models[i];
  m.shakePx = shakePx();  // (every model has the bank's shake)
  const TMotionNoise& n = m_motionNoise;
  if (!m_opts.adaptive_motion_noise || n.frames < m_opts.motion_noise_warmup || (i != n.general && i != n.rotation))
    return m;
  m.sigmaAngularPx = raisedNoise(m.sigmaAngularPx, n.angular2, m_opts.max_motion_noise_factor);
  return m;
}

double CImmSlamFilter::shakePx() const
{
  const double own = m_models.empty() ? 0.0 : m_models[0].shakePx;  // (the bank's shake_px, every model's)
  const TMotionNoise& n = m_motionNoise;
  if (!m_opts.adaptive_shake || n.shakeFrames < m_opts.motion_noise_warmup || !(own > 0)) return own;
  return raisedNoise(own, n.shake2, m_opts.max_shake_factor);
}

double CImmSlamFilter::loosestAngularNoisePx() const
{
  return m_motionNoise.general < 0 ? 0.0 : effectiveModel(m_motionNoise.general).sigmaAngularPx;
}

void CImmSlamFilter::learnMotionNoise()
{
  // Covariance matching of the state correction (Mehra 1972; Mohamed & Schwarz 1999, "Adaptive Kalman
  // filtering for INS/GPS"): a mode's angular velocity correction dw = w+ - w- has E[dw dw^T] =
  // P-_ww - P+_ww when its process noise is right. Where the camera accelerates more than the noise
  // says and the frame measures the rotation well (K_w H_w ~ I), dw dw^T exceeds that drop by the
  // missing noise: Q_true ~ dw dw^T - (P-_ww - P+_ww) + Q_used, per axis, in pixels (the
  // dimensionless formulation), blended with exponential forgetting. Learned on the loosest general
  // mode, whose correction shows the camera's accelerations best, in the frames that updated it: a
  // bank whose loosest mode is dormant (a slow or still camera) learns nothing. Angular only: it is
  // measured in the image without the map's scale, while the linear velocity is in the map's
  // arbitrary unit, and movers that pull the translation would pass for accelerations.
  TMotionNoise& n = m_motionNoise;
  if (!n.primed || m_dormant[n.general]) return;  // (primed: adaptive, with a general mode predicted in full)
  const auto& g = m_imm->mode(n.general);
  const Vec3 dw = g.x.segment<3>(motion::kW) - n.wPred;
  const double k = m_focal * m_focal / (n.dt * n.dt) / 3;  // per axis, px^2 per frame^2
  const double drop = k * (n.PwwPred - g.P.block<3, 3>(motion::kW, motion::kW)).trace();
  ++n.frames;
  // A frame whose angular velocity prior is wider than twice the process noise (the start, a
  // relocalisation) tells the prior, not the noise.
  if (drop >= 2 * n.usedAngular2) return;
  const double a = m_opts.adaptive_noise_rate;
  n.angular2 = (1 - a) * n.angular2 + a * (k * dw.squaredNorm() - drop + n.usedAngular2);
}

CImmSlamFilter::~CImmSlamFilter() = default;

void CImmSlamFilter::initialiseState()
{
  // World frame = first camera frame, known exactly (gauge); velocities with their priors.
  VecX x = VecX::Zero(motion::kCamDim);
  x[motion::kQ] = 1.0;
  MatX P = MatX::Zero(motion::kCamDim, motion::kCamDim);
  const double sv = m_opts.init_linear_velocity_std_px / m_focal;
  const double sw = m_opts.init_angular_velocity_std_px / m_focal;
  P.block<3, 3>(motion::kV, motion::kV) = Mat3::Identity() * sv * sv;
  P.block<3, 3>(motion::kW, motion::kW) = Mat3::Identity() * sw * sw;
  m_imm->setAllModes(x, P);
  m_features.clear();
  m_cloneFrames.clear();
  m_xFused = x;
  updateWorldPose();
}

void CImmSlamFilter::start(double timestamp)
{
  m_lastTimestamp = timestamp;
  m_xPred = m_xFused;
}

double CImmSlamFilter::frameDt(double t)
{
  const double delta = t - m_lastTimestamp;
  // A timestamp that does not advance counts as one frame and does not move the clock back: the
  // next frame's interval is measured from the latest time seen (callers should not send such
  // frames; the application skips them).
  if (delta > 0) m_lastTimestamp = t;
  if (m_opts.frame_rate_hz > 0)
    m_framePeriod = 1.0 / m_opts.frame_rate_hz;
  else if (delta > 0 && m_firstDeltas.size() < 9)
  {
    // Nominal period: median of the first deltas (robust to one dropped frame early on).
    m_firstDeltas.push_back(delta);
    std::vector<double> d = m_firstDeltas;
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    m_framePeriod = d[d.size() / 2];
  }
  if (!(delta > 0) || !(m_framePeriod > 0)) return 1.0;  // non-increasing timestamps: one frame
  // Time is counted in frames (dimensionless formulation): timestamp jitter within 10 % of a whole
  // number of periods is rounding (printed timestamps, clock ticks), not motion time.
  const double dt = delta / m_framePeriod;
  const double whole = std::round(dt);
  if (whole >= 1 && std::abs(dt - whole) < 0.1 * whole) return whole;
  return std::clamp(dt, 0.05, 1000.0);
}

double CImmSlamFilter::predict(double timestamp)
{
  const double dt = frameDt(timestamp);
  const int r = m_imm->numModels();
  m_logLik = VecX::Zero(r);
  m_dormantDecided = false;
  std::fill(m_dormant.begin(), m_dormant.end(), 0);
  m_dormantUse.clear();
  // The modes predicted now read only the lower triangle of their mixed covariance (the prediction
  // mirrors its result): the mixing skips their mirror. A lazy mode's is read by blocks: mirrored.
  std::vector<char> lazy(r), lowerOnly(r);
  for (int i = 0; i < r; ++i)
  {
    lazy[i] = m_lazyPrediction && m_wasDormant[i] && m_models[i].family != motion::EMotionFamily::Stationary;
    lowerOnly[i] = !lazy[i];
  }
  m_imm->mix(m_pool.get(), dt, &lowerOnly);
  m_pool->parallelFor(0, r, [&](int i) {
    auto& g = m_imm->mode(i);
    const auto inc = motion::motionIncrement(effectiveModel(i), g.x.segment<3>(motion::kV), g.x.segment<3>(motion::kW), dt,
                                             m_focal);
    TLazyMode& L = m_lazy[i];
    L.active = lazy[i];
    if (!L.active)
    {
      predictRobocentric(g, m_features, inc, m_scratch[i], r > 1, numClones());  // (one model: not mixed, full)
      return;
    }
    // Dormant in the previous frame: likely dormant again. Mean and transition blocks only.
    predictRobocentricMean(g, m_features, inc, L.blocks, numClones());
    if (inc.shakeCov.isZero())
      L.shake.resize(0, 0);
    else
      L.shake = shakeFactor(g, m_features, inc.shakeCov, numClones());
    L.blockAt.assign(g.x.size(), -1);
    for (int b = 0; b < static_cast<int>(L.blocks.size()); ++b) L.blockAt[L.blocks[b].off] = b;
  });
  // IMM-fused prediction (paper eqs. 10-11): the search regions of the whole bank. Only its mean is
  // formed; the covariance blocks the search and RANSAC need come from predictedCov*().
  if (r == 1)
    m_xPred = m_imm->mode(0).x;
  else
    m_imm->combine(m_imm->predictedProbabilities(), m_xPred, nullptr);
  // The loosest general mode's prediction, for learnMotionNoise (a lazy mode has no covariance yet).
  TMotionNoise& n = m_motionNoise;
  n.primed = m_opts.adaptive_motion_noise && n.general >= 0 && !m_lazy[n.general].active;
  n.dt = dt;  // (also learnShake's)
  if (n.primed)
  {
    const auto& g = m_imm->mode(n.general);
    n.wPred = g.x.segment<3>(motion::kW);
    n.PwwPred = g.P.block<3, 3>(motion::kW, motion::kW);
    const double used = effectiveModel(n.general).sigmaAngularPx;
    n.usedAngular2 = used * used;
  }
  return dt;
}

void CImmSlamFilter::materialize(int i)
{
  TLazyMode& L = m_lazy[i];
  if (!L.active) return;
  applyRobocentricTransition(m_imm->mode(i).P, L.blocks, m_scratch[i], L.shake.size() == 0);  // (one mirror)
  if (L.shake.size()) addCovarianceFactor(m_imm->mode(i).P, L.shake);
  L.active = false;
}

MatX CImmSlamFilter::modePredictedBlock(int i, int off, int len)
{
  const TLazyMode& L = m_lazy[i];
  if (L.active)
  {
    const int b = off < static_cast<int>(L.blockAt.size()) ? L.blockAt[off] : -1;
    if (b >= 0 && L.blocks[b].len == len)
    {
      MatX blk = transitionBlock(m_imm->mode(i).P, L.blocks[b]);
      if (L.shake.size()) blk.noalias() += L.shake.middleRows(off, len) * L.shake.middleRows(off, len).transpose();
      return blk;
    }
    materialize(i);  // not one transition block: predict the covariance after all
  }
  return m_imm->mode(i).P.block(off, off, len, len);
}

MatX CImmSlamFilter::modePredictedColumns(int i, int off, int len)
{
  const TLazyMode& L = m_lazy[i];
  if (L.active)
  {
    const int b = off < static_cast<int>(L.blockAt.size()) ? L.blockAt[off] : -1;
    if (b >= 0 && L.blocks[b].len == len)
    {
      MatX cols = transitionColumns(m_imm->mode(i).P, L.blocks, b);
      if (L.shake.size()) cols.noalias() += L.shake * L.shake.middleRows(off, len).transpose();
      return cols;
    }
    materialize(i);
  }
  return m_imm->mode(i).P.middleCols(off, len);
}

MatX CImmSlamFilter::predictedCovBlock(int off, int len)
{
  const int r = m_imm->numModels();
  if (r == 1) return m_imm->mode(0).P.block(off, off, len, len);
  if (std::none_of(m_lazy.begin(), m_lazy.end(), [](const TLazyMode& L) { return L.active; }))
    return m_imm->combinedBlock(m_imm->predictedProbabilities(), m_xPred, off, len);
  // Eq. (11) restricted to one block, with the lazy modes' blocks computed from their transition.
  const VecX& w = m_imm->predictedProbabilities();
  MatX B = MatX::Zero(len, len);
  for (int i = 0; i < r; ++i)
  {
    if (!(w[i] > 0)) continue;
    const VecX d = m_imm->mode(i).x.segment(off, len) - m_xPred.segment(off, len);
    B += w[i] * (modePredictedBlock(i, off, len) + d * d.transpose());
  }
  return B;
}

MatX CImmSlamFilter::predictedCovColumns(int off, int len)
{
  const int r = m_imm->numModels();
  if (r == 1) return m_imm->mode(0).P.middleCols(off, len);
  if (std::none_of(m_lazy.begin(), m_lazy.end(), [](const TLazyMode& L) { return L.active; }))
    return m_imm->combinedColumns(m_imm->predictedProbabilities(), m_xPred, off, len);
  const VecX& w = m_imm->predictedProbabilities();
  MatX C = MatX::Zero(m_xPred.size(), len);
  for (int i = 0; i < r; ++i)
  {
    if (!(w[i] > 0)) continue;
    const VecX d = m_imm->mode(i).x - m_xPred;
    C += w[i] * modePredictedColumns(i, off, len);
    C.noalias() += (w[i] * d) * d.segment(off, len).transpose();
  }
  return C;
}

void CImmSlamFilter::correctPose(const Vec3& r_CW, const Vec4& q_CW, double sigmaT, double sigmaTheta,
                                 const Vec6& velocity, const Mat6& velocityCov)
{
  const int r = m_imm->numModels();
  m_motionNoise.primed = false;  // the velocities restart: this frame tells nothing of the noise
  m_pool->parallelFor(0, r, [&](int i) {
    materialize(i);
    applyPoseCorrection(m_imm->mode(i), m_features, r_CW, q_CW, sigmaT, sigmaTheta, velocity, velocityCov,
                        m_scratch[i], numClones());
  });
  if (r == 1)
    m_xPred = m_imm->mode(0).x;
  else
    m_imm->combine(m_imm->predictedProbabilities(), m_xPred, nullptr);
}
}  // namespace immslam::slam
