/* imm-monoslam — 1-point RANSAC hypotheses on the (IMM-fused) EKF prediction. */
#include <immslam/core/config.h>
#include <immslam/slam/COnePointRansac.h>

#include <Eigen/Cholesky>
#include <cmath>

namespace immslam::slam
{
void COnePointRansac::TOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_DOUBLE(inlier_threshold_px);
  validate(s);
}

void COnePointRansac::TOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  MRPT_SAVE_CONFIG_VAR_COMMENT(inlier_threshold_px, "pixels: a match supports a hypothesis if closer than this");
}

void COnePointRansac::TOptions::validate(const std::string& s) const
{
  core::requirePositive(inlier_threshold_px, s, "inlier_threshold_px");
  core::requireInRange(success_probability, 0.5, 0.999999, s, "success_probability");
  core::requireInRange(max_hypotheses, 1, 100000, s, "max_hypotheses");
  core::requireInRange(rescue_probability, 0.5, 0.999999, s, "rescue_probability");
}

COnePointRansac::COnePointRansac() = default;

std::vector<int> COnePointRansac::lowInnovationInliers(const camera::CCameraModel& cam, const VecX& x,
                                                       const std::function<MatX(int, int)>& covColumns,
                                                       const std::vector<TFeature>& features,
                                                       const std::vector<TCandidate>& cands, std::mt19937& rng,
                                                       int* nHypotheses) const
{
  std::vector<int> best;
  const int m = static_cast<int>(cands.size());
  if (nHypotheses) *nHypotheses = 0;
  if (m == 0) return best;
  const double thr2 = m_opts.inlier_threshold_px * m_opts.inlier_threshold_px;
  double nHyp = m_opts.max_hypotheses;
  std::uniform_int_distribution<int> pick(0, m - 1);
  std::vector<int> support;
  support.reserve(m);
  VecX xh(x.size());
  int tried = 0;
  for (; tried < nHyp && tried < m_opts.max_hypotheses; ++tried)
  {
    const TCandidate& c = cands[pick(rng)];
    const TFeature& f = features[c.feature];
    // Mean-only update with this single match: x_i = x + P H^T S^-1 (z - h).
    const MatX PHt = covColumns(f.offset, f.dim()) * c.J_feat.transpose();
    xh = x;
    xh.noalias() += PHt * c.S.ldlt().solve(c.z - c.h);
    support.clear();
    for (int j = 0; j < m; ++j)
    {
      Vec2 uv;
      if (!predictMeasurement(cam, xh, features[cands[j].feature], uv)) continue;
      if ((uv - cands[j].z).squaredNorm() < thr2) support.push_back(j);
    }
    if (support.size() > best.size())
    {
      best = support;
      // Adaptive number of hypotheses: n = log(1-p) / log(1 - inlier ratio).
      const double eps = static_cast<double>(best.size()) / m;
      nHyp = eps >= 1.0 ? 1.0 : std::log(1 - m_opts.success_probability) / std::log(1 - eps);
    }
  }
  if (nHypotheses) *nHypotheses = tried;
  return best;
}
}  // namespace immslam::slam
