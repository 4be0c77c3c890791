/* imm-monoslam — augmentation, re-parametrization and normalization of SLAM Gaussians. */
#include <immslam/features/inverse_depth.h>
#include <immslam/math/quaternion.h>
#include <immslam/slam/state_ops.h>

namespace immslam::slam
{
void appendInverseDepthFeatures(bayes::TGaussian& g, const std::vector<TNewRay>& rays)
{
  if (rays.empty()) return;
  const Eigen::Index n = g.x.size();
  const Eigen::Index k = static_cast<Eigen::Index>(rays.size());
  g.x.conservativeResize(n + 6 * k);
  MatX P = MatX::Zero(n + 6 * k, n + 6 * k);
  P.topLeftCorner(n, n) = g.P;
  for (Eigen::Index i = 0; i < k; ++i)
  {
    const auto& ray = rays[i];
    features::Mat63 J_b;
    g.x.segment<6>(n + 6 * i) =
        features::initInverseDepth(Vec3::Zero(), Vec4(1, 0, 0, 0), ray.b_C, ray.rho, nullptr, nullptr, &J_b);
    // Chain rule: dy/d(uv) = dy/db * db/d(uv).
    const Eigen::Matrix<double, 6, 2> J_uv = J_b * ray.J_b_uv;
    auto B = P.block<6, 6>(n + 6 * i, n + 6 * i);
    B = ray.sigmaPixel * ray.sigmaPixel * J_uv * J_uv.transpose();
    B(5, 5) += ray.sigmaRho * ray.sigmaRho;
  }
  g.P = std::move(P);
}

void reparametrize(bayes::TGaussian& g, const std::vector<TReparamSegment>& segs)
{
  std::vector<int> newOff(segs.size());
  int nNew = 0;
  for (std::size_t a = 0; a < segs.size(); ++a)
  {
    newOff[a] = nNew;
    nNew += segs[a].newLen();
  }
  VecX x(nNew);
  MatX P(nNew, nNew);
  for (std::size_t a = 0; a < segs.size(); ++a)
  {
    const auto& sa = segs[a];
    x.segment(newOff[a], sa.newLen()) = sa.copy ? VecX(g.x.segment(sa.oldOffset, sa.oldLen)) : sa.newValue;
    for (std::size_t b = 0; b <= a; ++b)
    {
      const auto& sb = segs[b];
      const auto old = g.P.block(sa.oldOffset, sb.oldOffset, sa.oldLen, sb.oldLen);
      auto out = P.block(newOff[a], newOff[b], sa.newLen(), sb.newLen());
      if (sa.copy && sb.copy)
        out = old;
      else if (sa.copy)
        out.noalias() = old * sb.J.transpose();
      else if (sb.copy)
        out.noalias() = sa.J * old;
      else
        out.noalias() = sa.J * old * sb.J.transpose();
      if (a == b && !sa.copy)
      {
        const MatX sym = 0.5 * (out + out.transpose());
        out = sym;
      }
      if (b != a) P.block(newOff[b], newOff[a], sb.newLen(), sa.newLen()) = out.transpose();
    }
  }
  g.x = std::move(x);
  g.P = std::move(P);
}

void invertPoseClone(const Vec3& r, const Vec4& q, const MatX& P, Vec3& t, Vec4& qInv, Mat6& cov)
{
  const Vec4 qc = q.normalized();
  const Mat3 R = math::quatToRotation(qc);
  qInv = math::quatConjugate(qc);
  t = -(R.transpose() * r);
  Mat4 L;
  math::quatMultiply(math::quatConjugate(qc), qc, nullptr, &L);
  Eigen::Matrix<double, 6, 7> Jc = Eigen::Matrix<double, 6, 7>::Zero();
  Jc.topLeftCorner<3, 3>().setIdentity();
  Jc.bottomRightCorner<3, 4>() = 2.0 / q.norm() * L.bottomRows<3>();  // (through q / |q|)
  Mat6 Ji = Mat6::Zero();
  Ji.topLeftCorner<3, 3>() = -R.transpose();
  Ji.topRightCorner<3, 3>() = math::skew(t);
  Ji.bottomRightCorner<3, 3>() = -R;
  const Eigen::Matrix<double, 6, 7> J = Ji * Jc;
  cov = J * P * J.transpose();
  cov = (0.5 * (cov + cov.transpose())).eval();
}

void normalizeQuaternion(bayes::TGaussian& g)
{
  Mat4 J;
  const Vec4 qn = math::quatNormalized(g.x.segment<4>(3), &J);
  g.x.segment<4>(3) = qn;
  g.P.middleRows<4>(3) = J * g.P.middleRows<4>(3);
  g.P.middleCols<4>(3) = g.P.middleCols<4>(3) * J.transpose();
}
}  // namespace immslam::slam
