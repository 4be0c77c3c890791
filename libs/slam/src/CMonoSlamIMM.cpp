/* imm-monoslam — IMM monocular EKF SLAM: one frame = mix, predict, search, 1-point RANSAC,
 * update every mode, model probabilities (paper Fig. 2 and Sec. IV). Camera-centred state:
 * x = (r_CW, q_CW, v, w, features in the current camera frame). */
#include <immslam/features/inverse_depth.h>
#include <immslam/math/chi2.h>
#include <immslam/math/gaussian.h>
#include <immslam/math/parallel.h>
#include <immslam/math/quaternion.h>
#include <immslam/slam/CMonoSlamIMM.h>
#include <immslam/slam/measurement.h>
#include <immslam/slam/robocentric_prediction.h>
#include <immslam/slam/state_ops.h>

#include <Eigen/Cholesky>
#include <opencv2/core.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace immslam::slam
{
CMonoSlamIMM::CMonoSlamIMM(const TOptions& opts, const TIMMBankOptions& bank, const COnePointRansac::TOptions& ransac,
                           camera::CCameraModel::Ptr cam)
    : m_opts(opts), m_ransac(ransac), m_cam(std::move(cam)), m_rng(static_cast<unsigned>(opts.seed))
{
  if (!m_cam) throw std::invalid_argument("CMonoSlamIMM: no camera model");
  m_opts.validate("slam");
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
  m_lensMask = frontend::lensMask(*m_cam, detectionBorderPx());
  m_detectMask = m_lensMask;
  initialiseState();
}

void CMonoSlamIMM::setExclusionMask(const cv::Mat& excluded)
{
  if (!excluded.empty() &&
      (excluded.type() != CV_8UC1 || excluded.cols != m_cam->width() || excluded.rows != m_cam->height()))
    throw std::invalid_argument("CMonoSlamIMM::setExclusionMask: expected an empty mask or a CV_8UC1 image of " +
                                std::to_string(m_cam->width()) + "x" + std::to_string(m_cam->height()) + " pixels");
  m_excluded = frontend::growExclusion(excluded, m_opts.patch_half_size);
  m_detectMask = m_lensMask;
  if (m_excluded.empty()) return;
  m_detectMask = m_excluded == 0;
  if (!m_lensMask.empty()) cv::bitwise_and(m_detectMask, m_lensMask, m_detectMask);
}

CMonoSlamIMM::~CMonoSlamIMM() = default;

void CMonoSlamIMM::initialiseState()
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
  m_xFused = x;
  updateWorldPose();
}

double CMonoSlamIMM::frameDt(double t)
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

void CMonoSlamIMM::predict(double dt)
{
  const int r = m_imm->numModels();
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
    const auto inc = motion::motionIncrement(m_models[i], g.x.segment<3>(motion::kV), g.x.segment<3>(motion::kW), dt,
                                             m_focal);
    TLazyMode& L = m_lazy[i];
    L.active = lazy[i];
    if (!L.active)
    {
      predictRobocentric(g, m_features, inc, m_scratch[i], r > 1);  // (one model: not mixed, full)
      return;
    }
    // Dormant in the previous frame: likely dormant again. Mean and transition blocks only.
    predictRobocentricMean(g, m_features, inc, L.blocks);
    if (inc.shakeCov.isZero())
      L.shake.resize(0, 0);
    else
      L.shake = shakeFactor(g, m_features, inc.shakeCov);
    L.blockAt.assign(g.x.size(), -1);
    for (int b = 0; b < static_cast<int>(L.blocks.size()); ++b) L.blockAt[L.blocks[b].off] = b;
  });
  // IMM-fused prediction (paper eqs. 10-11): the search regions of the whole bank. Only its mean is
  // formed; the covariance blocks the search and RANSAC need come from predictedCov*().
  if (r == 1)
    m_xPred = m_imm->mode(0).x;
  else
    m_imm->combine(m_imm->predictedProbabilities(), m_xPred, nullptr);
}

void CMonoSlamIMM::materialize(int i)
{
  TLazyMode& L = m_lazy[i];
  if (!L.active) return;
  applyRobocentricTransition(m_imm->mode(i).P, L.blocks, m_scratch[i], L.shake.size() == 0);  // (one mirror)
  if (L.shake.size()) addCovarianceFactor(m_imm->mode(i).P, L.shake);
  L.active = false;
}

MatX CMonoSlamIMM::modePredictedBlock(int i, int off, int len)
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

MatX CMonoSlamIMM::modePredictedColumns(int i, int off, int len)
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

MatX CMonoSlamIMM::predictedCovBlock(int off, int len)
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

MatX CMonoSlamIMM::predictedCovColumns(int off, int len)
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

void CMonoSlamIMM::searchFeatures(const cv::Mat& grey, std::vector<TCandidate>& cands)
{
  Vec3 r_WC;
  Vec4 q_WC;
  worldPoseFromState(m_xPred, r_WC, q_WC);
  q_WC.normalize();
  frontend::TSearchParams sp;
  sp.gateChi2 = math::chi2Quantile(m_opts.search_probability, 2);
  sp.minScore = m_opts.min_ncc;
  sp.maxHalfExtentPx = m_opts.max_search_half_extent_px;
  const double margin = m_opts.patch_half_size + 1;

  // Predict every feature (cheap), then search the visible ones (the image work) in parallel.
  struct TJob
  {
    int k;
    Vec2 h;
    Mat2F Jf;
    Mat2 S;
    frontend::TSearchResult res;
  };
  std::vector<TJob> jobs;
  jobs.reserve(m_features.size());
  for (int k = 0; k < static_cast<int>(m_features.size()); ++k)
  {
    TJob j;
    j.k = k;
    if (!m_features[k].patch.valid()) continue;
    if (!predictMeasurement(*m_cam, m_xPred, m_features[k], j.h, &j.Jf)) continue;
    if (!m_cam->isInImage(j.h, margin)) continue;
    jobs.push_back(j);
  }
  std::vector<cv::Mat> templates(jobs.size());
  m_pool->parallelFor(0, static_cast<int>(jobs.size()), [&](int idx) {
    TJob& j = jobs[idx];
    const TFeature& f = m_features[j.k];
    // S_i = H_i P H_i^T + R with the fused P (eq. 14): only the feature's own block is needed (a
    // feature block: read-only, also for lazy modes).
    j.S = innovationCovariance(predictedCovBlock(f.offset, f.dim()), j.Jf, m_sigmaPixel);
    Mat2 A = Mat2::Identity();
    if (m_opts.warp_patches)
    {
      const Vec3 p = math::quatRotate(q_WC, featurePointInCamera(m_xPred, f)) + r_WC;
      Vec3 n = f.r0 - p;
      if (n.norm() > 0) n.normalize();
      A = frontend::patchWarp(*m_cam, f.r0, f.q0, r_WC, q_WC, p, n);
    }
    templates[idx] = f.patch.predictTemplate(A);
    j.res = frontend::searchInEllipse(grey, templates[idx], j.h, j.S, sp);
  });
  // Expanded search: when the motion was not predicted (an acceleration beyond every model), most
  // matches fall outside their ellipses together. The features not found are searched again in
  // ellipses grown by expand_search_factor; 1-point RANSAC then decides with the filter's own S
  // (a hypothesis from one such match must be supported by the others).
  int nFound = 0;
  for (const auto& j : jobs) nFound += j.res.found ? 1 : 0;
  if (m_opts.expand_search_factor > 1 && !jobs.empty() && nFound < m_opts.expand_below_fraction * jobs.size())
  {
    m_report.expandedSearch = true;
    const double k2 = m_opts.expand_search_factor * m_opts.expand_search_factor;
    m_pool->parallelFor(0, static_cast<int>(jobs.size()), [&](int idx) {
      TJob& j = jobs[idx];
      if (!j.res.found) j.res = frontend::searchInEllipse(grey, templates[idx], j.h, j.S * k2, sp);
    });
  }

  // Excluded pixels (setExclusionMask): a match there is not the feature's.
  for (auto& j : jobs)
    if (j.res.found && frontend::maskedAt(m_excluded, j.res.uv)) j.res.found = false;
  double areaSum = 0;
  for (const auto& j : jobs)
  {
    TFeature& f = m_features[j.k];
    f.nPredicted++;
    f.lastSeenFrame = m_frame;
    areaSum += frontend::ellipseArea(j.S, sp.gateChi2);
    TSearchRecord rec;
    rec.id = f.id;
    rec.h = j.h;
    rec.S = j.S;
    rec.found = j.res.found;
    rec.z = j.res.uv;
    rec.score = j.res.score;
    m_report.searches.push_back(rec);
    if (j.res.found) cands.push_back(TCandidate{j.k, j.res.uv, j.h, j.Jf, j.S});
  }
  m_report.nPredicted = static_cast<int>(jobs.size());
  m_report.meanSearchAreaPx2 = jobs.empty() ? 0.0 : areaSum / jobs.size();
  m_report.nFound = static_cast<int>(cands.size());
}

void CMonoSlamIMM::buildMeasurement(const bayes::TGaussian& g, const std::vector<TCandidate>& cands,
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

double CMonoSlamIMM::modeLogLikelihood(int i, const bayes::CSparseJacobian& H, const VecX& nu, const VecX& Rdiag,
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

void CMonoSlamIMM::updateBank(const std::vector<TCandidate>& cands, const std::vector<int>& which, VecX& logLik)
{
  const int r = m_imm->numModels();
  if (which.empty()) return;
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
  if (m == 0) return;
  constexpr double kNoLik = -std::numeric_limits<double>::infinity();
  const VecX Rdiag = VecX::Constant(2 * m, m_sigmaPixel * m_sigmaPixel);

  if (m_dormantBelow > 0 && !m_dormantDecided)
  {
    // First update of the frame: every mode's likelihood first (cheap), then the dormant set, then the
    // covariance update of the others only. The likelihood is the one ekfUpdate() would report.
    VecX ll(r);
    m_pool->parallelFor(0, r, [&](int i) {
      bayes::CSparseJacobian H;
      VecX nu;
      buildMeasurement(m_imm->mode(i), cands, use, H, nu);
      ll[i] = modeLogLikelihood(i, H, nu, Rdiag, &m_factors[i]);
    });
    VecX a(r);
    for (int i = 0; i < r; ++i) a[i] = std::log(std::max(m_imm->predictedProbabilities()[i], 1e-300)) + ll[i];
    const double lse = math::logSumExp(a);
    if (std::isfinite(lse))
    {
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
    m_dormantDecided = true;
    m_dormantUse = use;
    m_pool->parallelFor(0, r, [&](int i) {
      logLik[i] += ll[i];
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
  else
  {
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
    m_pool->parallelFor(0, r, [&](int i) {
      auto& g = m_imm->mode(i);
      bayes::CSparseJacobian H;
      VecX nu;
      if (m_dormant[i])
      {
        buildMeasurement(g, cands, joint, H, nu);
        logLik[i] = modeLogLikelihood(i, H, nu, RdiagJoint);
        return;
      }
      materialize(i);
      buildMeasurement(g, cands, use, H, nu);
      const auto res = bayes::ekfUpdate(g.x, g.P, H, nu, Rdiag);
      logLik[i] += res.ok ? res.logLikelihood : kNoLik;
      normalizeQuaternion(g);
    });
  }
  for (int c : use) m_features[cands[c].feature].nMatched++;
  m_report.nMatched += m;
}

void CMonoSlamIMM::settleDormantModes()
{
  const int r = m_imm->numModels();
  m_report.nDormantModes = 0;
  m_report.nLazyModes = 0;
  for (int i = 0; i < r; ++i)
  {
    m_report.nDormantModes += m_dormant[i] ? 1 : 0;
    m_report.nLazyModes += m_dormant[i] && m_lazy[i].active ? 1 : 0;
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
}

std::vector<int> CMonoSlamIMM::rescue(const std::vector<TCandidate>& cands, const std::vector<char>& used)
{
  // Fused estimate after the first update with weights w (eqs. 10-11 applied to the updated modes).
  const int r = m_imm->numModels();
  const VecX& w = m_rescueWeights;
  VecX xf = m_imm->mode(0).x;
  if (r > 1) m_imm->combine(w, xf, nullptr);
  const double gate = math::chi2Quantile(m_ransac.options().rescue_probability, 2);
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
    if (nu.dot(S.ldlt().solve(nu)) < gate) out.push_back(c);
  }
  return out;
}

void CMonoSlamIMM::estimateMeasurementNoise(const std::vector<TCandidate>& cands, const std::vector<int>& inliers)
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

void CMonoSlamIMM::updateWorldPose()
{
  worldPoseFromState(m_xFused, m_rWC, m_qWC);
  m_qWC.normalize();
}
}  // namespace immslam::slam
