/* imm-monoslam — NEES, chi-square bands and pose errors for consistency tests. */
#include <immslam/eval/consistency.h>
#include <immslam/math/chi2.h>
#include <immslam/math/quaternion.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace immslam::eval
{
double nees(const VecX& err, const MatX& P)
{
  if (P.rows() != P.cols() || P.rows() != err.size())
    throw std::invalid_argument("nees: error of size " + std::to_string(err.size()) +
                                " with a " + std::to_string(P.rows()) + "x" + std::to_string(P.cols()) +
                                " covariance");
  const double inf = std::numeric_limits<double>::infinity();
  if (!err.allFinite() || !P.allFinite()) return inf;
  const Eigen::LLT<MatX> llt(P);
  if (llt.info() != Eigen::Success) return inf;
  const VecX z = llt.matrixL().solve(err);  // e^T P^-1 e = |L^-1 e|^2
  const double v = z.squaredNorm();
  return std::isfinite(v) ? v : inf;
}

TChi2Band averageNeesBand(int dof, int nRuns, double confidence)
{
  if (dof < 1 || nRuns < 1 || !(confidence > 0 && confidence < 1))
    throw std::invalid_argument("averageNeesBand: need dof >= 1, nRuns >= 1, 0 < confidence < 1");
  TChi2Band b;
  b.confidence = confidence;
  b.dof = dof;
  b.nRuns = nRuns;
  const int n = dof * nRuns;
  b.lower = math::chi2Quantile(0.5 * (1 - confidence), n) / nRuns;
  b.upper = math::chi2Quantile(0.5 * (1 + confidence), n) / nRuns;
  return b;
}

CNeesAccumulator::CNeesAccumulator(int dof) : m_dof(dof)
{
  if (dof < 1) throw std::invalid_argument("CNeesAccumulator: dof must be >= 1");
}

void CNeesAccumulator::add(size_t step, double neesValue)
{
  if (step >= m_sum.size())
  {
    m_sum.resize(step + 1, 0.0);
    m_count.resize(step + 1, 0);
  }
  m_sum[step] += neesValue;
  ++m_count[step];
}

void CNeesAccumulator::add(size_t step, const VecX& err, const MatX& P)
{
  if (err.size() != m_dof)
    throw std::invalid_argument("CNeesAccumulator::add: error of size " + std::to_string(err.size()) +
                                ", expected dof = " + std::to_string(m_dof));
  add(step, nees(err, P));
}

size_t CNeesAccumulator::runsAt(size_t step) const { return step < m_count.size() ? m_count[step] : 0; }

double CNeesAccumulator::averageAt(size_t step) const
{
  const size_t n = runsAt(step);
  return n ? m_sum[step] / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
}

std::vector<double> CNeesAccumulator::averages() const
{
  std::vector<double> a(m_sum.size());
  for (size_t k = 0; k < a.size(); ++k) a[k] = averageAt(k);
  return a;
}

double CNeesAccumulator::overallAverage() const
{
  double s = 0;
  size_t n = 0;
  for (size_t k = 0; k < m_sum.size(); ++k)
  {
    s += m_sum[k];
    n += m_count[k];
  }
  return n ? s / static_cast<double>(n) : std::numeric_limits<double>::quiet_NaN();
}

double CNeesAccumulator::fractionInsideBand(double confidence) const
{
  size_t steps = 0, inside = 0;
  for (size_t k = 0; k < m_sum.size(); ++k)
  {
    if (!m_count[k]) continue;
    ++steps;
    if (averageNeesBand(m_dof, static_cast<int>(m_count[k]), confidence).contains(averageAt(k))) ++inside;
  }
  return steps ? static_cast<double>(inside) / static_cast<double>(steps)
               : std::numeric_limits<double>::quiet_NaN();
}

Vec6 poseError6(const Vec3& p_est, const Vec4& q_est, const Vec3& p_true, const Vec4& q_true)
{
  Vec6 e;
  e.head<3>() = p_est - p_true;
  e.tail<3>() = math::quatToRotationVector(math::quatMultiply(math::quatConjugate(q_true), q_est));
  return e;
}

Mat6 poseCovariance6(const Vec4& q_est, const MatX& P_rq, Mat34* J_theta_q)
{
  if (P_rq.rows() != 7 || P_rq.cols() != 7)
    throw std::invalid_argument("poseCovariance6: P_rq must be 7x7 (covariance of [r; q]), got " +
                                std::to_string(P_rq.rows()) + "x" + std::to_string(P_rq.cols()));
  // Chain rule: theta = Log(qhat^* (x) q) ~ 2 vec(qhat^* (x) q) near q = qhat, and
  // d(qhat^* (x) q)/dq = L(qhat^*), the left-multiplication matrix (quatMultiply's J_q2).
  Mat4 L;
  math::quatMultiply(math::quatConjugate(q_est), q_est, nullptr, &L);
  const Mat34 J = 2.0 * L.bottomRows<3>();
  Eigen::Matrix<double, 6, 7> G = Eigen::Matrix<double, 6, 7>::Zero();
  G.topLeftCorner<3, 3>().setIdentity();
  G.bottomRightCorner<3, 4>() = J;
  if (J_theta_q) *J_theta_q = J;
  return G * P_rq * G.transpose();
}

double poseNees(const Vec3& p_est, const Vec4& q_est, const Vec3& p_true, const Vec4& q_true,
                const MatX& P_rq)
{
  return nees(poseError6(p_est, q_est, p_true, q_true), poseCovariance6(q_est, P_rq));
}
}  // namespace immslam::eval
