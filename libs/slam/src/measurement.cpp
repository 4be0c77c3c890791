/* imm-monoslam — measurement model h(x) of the camera-centred SLAM filter. */
#include <immslam/features/inverse_depth.h>
#include <immslam/math/quaternion.h>
#include <immslam/slam/measurement.h>

#include <algorithm>

namespace immslam::slam
{
bool predictMeasurement(const camera::CCameraModel& cam, const VecX& x, const TFeature& f, Vec2& uv, Mat2F* J_feat)
{
  features::Mat36 J_h_y;
  Vec3 hC;
  if (f.kind == EFeatureKind::InverseDepth)
    hC = features::inverseDepthRay(x.segment<6>(f.offset), J_feat ? &J_h_y : nullptr);
  else
    hC = x.segment<3>(f.offset);
  Mat23 J_uv_h;
  if (!cam.project(hC, uv, J_feat ? &J_uv_h : nullptr)) return false;
  // Chain rule: dh/dy = d(uv)/d(h^C) * d(h^C)/dy.
  if (J_feat)
  {
    if (f.kind == EFeatureKind::InverseDepth)
      *J_feat = J_uv_h * J_h_y;
    else
      *J_feat = J_uv_h;
  }
  return true;
}

Vec3 featurePointInCamera(const VecX& x, const TFeature& f, double rhoMin)
{
  if (f.kind == EFeatureKind::XYZ) return x.segment<3>(f.offset);
  Vec6 y = x.segment<6>(f.offset);
  y[5] = std::max(y[5], rhoMin);
  return features::inverseDepthToPoint(y);
}

Mat2 innovationCovariance(const Eigen::Ref<const MatX>& Pff, const Mat2F& J_feat, double sigmaPixel)
{
  Mat2 S = J_feat * Pff * J_feat.transpose();
  S = 0.5 * (S + S.transpose()).eval();
  S.diagonal().array() += sigmaPixel * sigmaPixel;
  return S;
}

void worldPoseFromState(const VecX& x, Vec3& r_WC, Vec4& q_WC, Eigen::Matrix<double, 7, 7>* J)
{
  const Vec4 q_CW = x.segment<4>(3);
  q_WC = math::quatConjugate(q_CW);
  Mat34 J_q;
  Mat3 R_WC;
  r_WC = -math::quatRotate(q_WC, x.segment<3>(0), J ? &J_q : nullptr, &R_WC);
  if (J)
  {
    // Chain rule: r_WC = -R(conj(q_CW)) r_CW, q_WC = conj(q_CW).
    J->setZero();
    J->topLeftCorner<3, 3>() = -R_WC;
    J->topRightCorner<3, 4>() = -J_q * Vec4(1, -1, -1, -1).asDiagonal();
    J->bottomRightCorner<4, 4>() = Vec4(1, -1, -1, -1).asDiagonal();
  }
}
}  // namespace immslam::slam
