/* imm-monoslam — the IMM SLAM filter's update with given matches: every mode with its own
 * linearisation, the dormant modes (the bank's policy), the high-innovation rescue gate, model
 * probabilities (paper eq. 3), fusion (Fig. 2 step 4) and the adaptive pixel noise. */
#include <immslam/math/chi2.h>
#include <immslam/math/gaussian.h>
#include <immslam/math/parallel.h>
#include <immslam/slam/CImmSlamFilter.h>
#include <immslam/slam/measurement.h>
#include <immslam/slam/robocentric_prediction.h>
#include <immslam/slam/state_ops.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

namespace immslam::slam
{
namespace
{
/** What a motion family estimates: general (v, w) > rotation (w) > stationary (nothing). */
int familyRank(const motion::TMotionModel& m)
{
  switch (m.family)
  {
    case motion::EMotionFamily::General: return 2;
    case motion::EMotionFamily::Rotation: return 1;
    default: return 0;
  }
}
}  // namespace

void CImmSlamFilter::buildMeasurement(const bayes::TGaussian& g, const std::vector<TCandidate>& cands,
                                      const std::vector<int>& use, bayes::CSparseJacobian& H, VecX& nu) const
{
  const int m = static_cast<int>(use.size());
  H.resize(2 * m, static_cast<int>(g.x.size()));
  nu.resize(2 * m);
  for (int a = 0; a < m; ++a)
  {
    const TCandidate& c = cands[use[a]];
    const TFeature& f = m_features[c.feature];
    Vec2 h;
    Mat2F Jf;
    predictMeasurement(*m_cam, g.x, f, h, &Jf);  // each mode linearizes at its own estimate
    nu.segment<2>(2 * a) = c.z - h;
    H.addBlock(2 * a, f.offset, Jf);
  }
}

double CImmSlamFilter::modeLogLikelihood(int i, const bayes::CSparseJacobian& H, const VecX& nu, const VecX& Rdiag,
                                         bayes::TInnovationFactors* keep) const
{
  const TLazyMode& L = m_lazy[i];
  if (keep) keep->ok = false;
  if (!L.active)
  {
    const auto res = bayes::ekfLogLikelihood(m_imm->mode(i).P, H, nu, Rdiag, nullptr, keep);
    return res.ok ? res.logLikelihood : -std::numeric_limits<double>::infinity();
  }
  // S = H A P~ A^T H^T + R without forming A P~ A^T (O(n m)).
  MatX S = transitionInnovationCovariance(m_imm->mode(i).P, L.blocks, L.blockAt, H);
  if (L.shake.size())
  {
    const MatX HF = H.times(L.shake);
    S.noalias() += HF * HF.transpose();
  }
  S = 0.5 * (S + S.transpose());
  S.diagonal() += Rdiag;
  return math::gaussianLogLikelihood(nu, S);
}

int CImmSlamFilter::update(const std::vector<TCandidate>& cands, const std::vector<int>& which)
{
  const int r = m_imm->numModels();
  if (which.empty()) return 0;
  // Every mode must be able to predict every measurement: same data for all likelihoods.
  std::vector<int> use;
  for (int c : which)
  {
    bool ok = true;
    for (int i = 0; i < r && ok; ++i)
    {
      Vec2 uv;
      ok = predictMeasurement(*m_cam, m_imm->mode(i).x, m_features[cands[c].feature], uv);
    }
    if (ok) use.push_back(c);
  }
  const int m = static_cast<int>(use.size());
  if (m == 0) return 0;
  const VecX Rdiag = VecX::Constant(2 * m, m_sigmaPixel * m_sigmaPixel);
  if (m_dormantBelow > 0 && !m_dormantDecided)
    firstUpdate(cands, use, Rdiag);
  else
    laterUpdate(cands, use, Rdiag);
  for (int c : use) m_features[cands[c].feature].nMatched++;
  return m;
}

void CImmSlamFilter::chooseDormantModes(const VecX& a)
{
  const int r = m_imm->numModels();
  const double lse = math::logSumExp(a);
  if (!std::isfinite(lse)) return;
  int best = 0;
  a.maxCoeff(&best);
  for (int i = 0; i < r; ++i) m_dormant[i] = i != best && std::exp(a[i] - lse) < m_dormantBelow ? 1 : 0;
  // A dormant mode later takes the posterior of an updated mode that estimates at least what it
  // estimates (general > rotation > stationary: the velocities a rotation or stationary mode holds
  // at zero with zero variance must not overwrite a general mode's). Keep one such mode updated.
  for (int rank = 2; rank >= 1; --rank)
  {
    int pick = -1;
    bool covered = false;
    for (int i = 0; i < r; ++i)
      if (familyRank(m_models[i]) >= rank)
      {
        covered = covered || !m_dormant[i];
        if (pick < 0 || a[i] > a[pick]) pick = i;
      }
    if (!covered && pick >= 0) m_dormant[pick] = 0;
  }
}

void CImmSlamFilter::firstUpdate(const std::vector<TCandidate>& cands, const std::vector<int>& use, const VecX& Rdiag)
{
  // Every mode's likelihood first (cheap), then the dormant set, then the covariance update of the
  // others only. The likelihood is the one ekfUpdate() would report.
  const int r = m_imm->numModels();
  VecX ll(r);
  m_pool->parallelFor(0, r, [&](int i) {
    bayes::CSparseJacobian H;
    VecX nu;
    buildMeasurement(m_imm->mode(i), cands, use, H, nu);
    ll[i] = modeLogLikelihood(i, H, nu, Rdiag, &m_factors[i]);
  });
  VecX a(r);
  for (int i = 0; i < r; ++i) a[i] = std::log(std::max(m_imm->predictedProbabilities()[i], 1e-300)) + ll[i];
  chooseDormantModes(a);
  m_dormantDecided = true;
  m_dormantUse = use;
  m_pool->parallelFor(0, r, [&](int i) {
    m_logLik[i] += ll[i];
    if (m_dormant[i]) return;  // stays at its prediction
    materialize(i);            // a lazy mode the frame makes active (it kept no factors)
    auto& g = m_imm->mode(i);
    bayes::CSparseJacobian H;
    VecX nu;
    buildMeasurement(g, cands, use, H, nu);
    bayes::ekfUpdate(g.x, g.P, H, nu, Rdiag, &m_factors[i]);  // P H^T and chol(S) of the likelihood above
    normalizeQuaternion(g);
  });
}

void CImmSlamFilter::laterUpdate(const std::vector<TCandidate>& cands, const std::vector<int>& use, const VecX& Rdiag)
{
  constexpr double kNoLik = -std::numeric_limits<double>::infinity();
  m_dormantDecided = true;
  // A dormant mode is still at its prediction: its likelihood of every measurement of the frame is
  // the joint one of all of them (eq. 3), which replaces the first update's.
  std::vector<int> joint;
  if (std::find(m_dormant.begin(), m_dormant.end(), 1) != m_dormant.end())
  {
    joint = m_dormantUse;
    joint.insert(joint.end(), use.begin(), use.end());
    m_dormantUse = joint;
  }
  const VecX RdiagJoint = VecX::Constant(2 * static_cast<int>(joint.size()), m_sigmaPixel * m_sigmaPixel);
  m_pool->parallelFor(0, m_imm->numModels(), [&](int i) {
    auto& g = m_imm->mode(i);
    bayes::CSparseJacobian H;
    VecX nu;
    if (m_dormant[i])
    {
      buildMeasurement(g, cands, joint, H, nu);
      m_logLik[i] = modeLogLikelihood(i, H, nu, RdiagJoint);
      return;
    }
    materialize(i);
    buildMeasurement(g, cands, use, H, nu);
    const auto res = bayes::ekfUpdate(g.x, g.P, H, nu, Rdiag);
    m_logLik[i] += res.ok ? res.logLikelihood : kNoLik;
    normalizeQuaternion(g);
  });
}

CImmSlamFilter::TModeActivity CImmSlamFilter::finishUpdate()
{
  if (m_imm->numModels() > 1) m_imm->updateProbabilities(m_logLik);
  if (m_dormantDecided) learnMotionNoise();  // (a frame with an update)
  m_motionNoise.primed = false;
  const TModeActivity act = settleDormantModes();
  refreshFused();
  return act;
}

CImmSlamFilter::TModeActivity CImmSlamFilter::settleDormantModes()
{
  const int r = m_imm->numModels();
  TModeActivity act;
  for (int i = 0; i < r; ++i)
  {
    act.nDormant += m_dormant[i] ? 1 : 0;
    act.nLazy += m_dormant[i] && m_lazy[i].active ? 1 : 0;
  }
  m_wasDormant = m_dormant;
  // Source of each dormant mode: the most probable updated mode of an equal or richer family.
  const VecX& mu = m_imm->probabilities();
  std::vector<int> source(r, -1);
  for (int i = 0; i < r; ++i)
    if (m_dormant[i])
      for (int j = 0; j < r; ++j)
        if (!m_dormant[j] && familyRank(m_models[j]) >= familyRank(m_models[i]) &&
            (source[i] < 0 || mu[j] > mu[source[i]]))
          source[i] = j;
  // A lazy mode without a source (a frame without measurements): its prediction is its posterior.
  m_pool->parallelFor(0, r, [&](int i) {
    if (source[i] < 0) materialize(i);
  });
  // The others take their source's posterior, shared rather than copied (bitwise the same; the next
  // mixing reads it as their input).
  for (int i = 0; i < r; ++i)
    if (source[i] >= 0)
    {
      m_imm->aliasMode(i, source[i]);
      m_lazy[i].active = false;
    }
  std::fill(m_dormant.begin(), m_dormant.end(), 0);
  return act;
}

std::vector<int> CImmSlamFilter::rescueGate(const std::vector<TCandidate>& cands, const std::vector<char>& used,
                                            double gateChi2)
{
  // Weights: mu_{k|k-1} L^(1) normalized in log space; dormant modes are still at their prediction,
  // the test uses the updated ones.
  const int r = m_imm->numModels();
  VecX w = VecX::Ones(r);
  if (r > 1)
  {
    VecX a(r);
    for (int i = 0; i < r; ++i) a[i] = std::log(std::max(m_imm->predictedProbabilities()[i], 1e-300)) + m_logLik[i];
    const double lse = math::logSumExp(a);
    w = std::isfinite(lse) ? VecX((a.array() - lse).exp()) : m_imm->predictedProbabilities();
    for (int i = 0; i < r; ++i)
      if (m_dormant[i]) w[i] = 0;
    if (w.sum() > 0) w /= w.sum();
  }
  // Fused estimate after the first update with weights w (eqs. 10-11 applied to the updated modes).
  VecX xf = m_imm->mode(0).x;
  if (r > 1) m_imm->combine(w, xf, nullptr);
  std::vector<int> out;
  for (int c = 0; c < static_cast<int>(cands.size()); ++c)
  {
    if (used[c]) continue;
    const TFeature& f = m_features[cands[c].feature];
    Vec2 h;
    Mat2F Jf;
    if (!predictMeasurement(*m_cam, xf, f, h, &Jf)) continue;
    Mat2 S = Mat2::Zero();
    for (int i = 0; i < r; ++i)
    {
      if (!(w[i] > 0)) continue;  // (dormant modes: still at their prediction)
      const auto& g = m_imm->mode(i);
      S += w[i] * innovationCovariance(g.P.block(f.offset, f.offset, f.dim(), f.dim()), Jf, 0.0);
      if (r > 1)
      {
        // Spread term H (x_i - x)(x_i - x)^T H^T of eq. (11) through the sparse H.
        const Vec2 hd = Jf * (g.x.segment(f.offset, f.dim()) - xf.segment(f.offset, f.dim()));
        S += w[i] * hd * hd.transpose();
      }
    }
    S.diagonal().array() += m_sigmaPixel * m_sigmaPixel;
    const Vec2 nu = cands[c].z - h;
    if (nu.dot(S.ldlt().solve(nu)) < gateChi2) out.push_back(c);
  }
  return out;
}

void CImmSlamFilter::adaptMeasurementNoise(const std::vector<TCandidate>& cands, const std::vector<int>& inliers)
{
  // Post-fit residuals e = z - h(x+) of the inliers satisfy E[e e^T] = R - H P+ H^T (Myers & Tapley):
  // per pixel coordinate, sigma^2 ~ mean(|e|^2 + tr(H P+ H^T)) / 2. The frame's estimate is blended in
  // with exponential forgetting and kept within bounds.
  if (!m_opts.adaptive_pixel_noise || inliers.size() < 5) return;
  double sum = 0;
  int n = 0;
  for (int c : inliers)
  {
    const TFeature& f = m_features[cands[c].feature];
    Vec2 h;
    Mat2F Jf;
    if (!predictMeasurement(*m_cam, m_xFused, f, h, &Jf)) continue;
    const Mat2 HPH = innovationCovariance(fusedCovarianceBlock(f.offset, f.dim()), Jf, 0.0);
    sum += (cands[c].z - h).squaredNorm() + HPH.trace();
    ++n;
  }
  if (n < 5) return;
  const double var = sum / (2.0 * n);
  const double a = m_opts.adaptive_noise_rate;
  const double s2 = (1 - a) * m_sigmaPixel * m_sigmaPixel + a * var;
  m_sigmaPixel = std::clamp(std::sqrt(s2), m_opts.min_sigma_pixel, m_opts.max_sigma_pixel);
}

void CImmSlamFilter::learnShake(const std::vector<TCandidate>& cands, const std::vector<int>& inliers)
{
  // Covariance matching of the camera's shake (a rotation jitter after the motion, TIMMBankOptions::
  // shake_px) on the innovations nu = z - h(x_hat) of the frame's inliers at the fused prediction, the
  // innovation form of Mehra (1972) as learnMotionNoise's is the correction form. A shake moves every
  // feature alike, so it is read from the median of the innovations (per image axis), which a minority
  // of movers among the inliers cannot move; a feature's own errors (depth, pixel noise) are not
  // common and average out in it. Without missing noise, E[|med nu|^2] / 2 is at most the median
  // per-axis predicted spread tr(S - R) / 2 (the camera's share of it is common to every feature)
  // plus the median's share of the pixel noise, pi/2 sigma^2 / n; what it exceeds, per frame, is shake
  // the prediction lacks: q = |med nu|^2 / 2 - median tr(S - R) / 2 - pi sigma^2 / (2 n) + q_used,
  // blended with the pixel noise's forgetting rate. Only a frame with at least 8 inliers speaks.
  TMotionNoise& n = m_motionNoise;
  if (!m_opts.adaptive_shake || inliers.size() < 8 || m_models.empty()) return;
  const double own = m_models[0].shakePx;  // (the bank's shake_px, every model's)
  if (!(own > 0)) return;
  const int m = static_cast<int>(inliers.size());
  std::vector<double> u(m), v(m), spread(m);
  const double s2 = m_sigmaPixel * m_sigmaPixel;  // (the noise the frame's S were formed with)
  for (int k = 0; k < m; ++k)
  {
    const TCandidate& c = cands[inliers[k]];
    const Vec2 nu = c.z - c.h;
    u[k] = nu.x();
    v[k] = nu.y();
    spread[k] = std::max(0.0, 0.5 * c.S.trace() - s2);
  }
  const auto median = [](std::vector<double>& a) {
    std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(a.size() / 2), a.end());
    return a[a.size() / 2];
  };
  const double mu = median(u), mv = median(v), common = median(spread);
  const double used = shakePx();
  if (n.shake2 < 0) n.shake2 = own * own;
  constexpr double kHalfPi = 1.57079632679489662;
  const double dt = std::max(n.dt, 1e-3);  // (the variance of a random walk per frame)
  const double q = std::max(0.0, (0.5 * (mu * mu + mv * mv) - common - kHalfPi * s2 / m) / dt + used * used);
  const double a = m_opts.adaptive_noise_rate;
  n.shake2 = (1 - a) * n.shake2 + a * q;
  ++n.shakeFrames;
}
}  // namespace immslam::slam
