/* imm-monoslam — frames and parametrizations for MRPT's viewer objects. */
#include <immslam/math/quaternion.h>
#include <immslam/viz/mrpt_conversions.h>

#include <mrpt/math/CMatrixFixed.h>

#include <Eigen/Cholesky>
#include <Eigen/Dense>

#include <cmath>

namespace immslam::viz
{
namespace
{
mrpt::poses::CPose3D poseFromRt(const Mat3& R, const Vec3& t)
{
  mrpt::math::CMatrixDouble33 Rm;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Rm(r, c) = R(r, c);
  mrpt::math::CVectorFixedDouble<3> tm;
  for (int r = 0; r < 3; ++r) tm[r] = t[r];
  return mrpt::poses::CPose3D(Rm, tm);
}

/** R_B_C: optical axes in MRPT body axes (x fwd = z_C, y left = -x_C, z up = -y_C). */
Mat3 rotationBodyFromOptical()
{
  Mat3 R;
  R << 0, 0, 1,  //
      -1, 0, 0,  //
      0, -1, 0;
  return R;
}
}  // namespace

mrpt::poses::CPose3D toMrptPose(const core::TStampedPose& pose)
{
  const Vec4 q = pose.q_W_C.norm() > 0 ? Vec4(pose.q_W_C.normalized()) : Vec4(1, 0, 0, 0);
  return poseFromRt(math::quatToRotation(q), pose.p_W_C);
}

mrpt::poses::CPose3D opticalToMrptBody()
{
  // T_C_B = (T_B_C)^-1 with T_B_C = CPose3D(0,0,0,-90deg,0,-90deg).
  return poseFromRt(rotationBodyFromOptical().transpose(), Vec3::Zero());
}

mrpt::poses::CPose3D displayFromWorld() { return poseFromRt(rotationBodyFromOptical(), Vec3::Zero()); }

TMrptInverseDepth inverseDepthToMrpt(const TInverseDepthView& f)
{
  // Object axes in W: x_obj -> z_W, y_obj -> x_W, z_obj -> y_W, so that
  // R (cos y cos p, sin y cos p, -sin p) = (cos p sin y, -sin p, cos p cos y) = m(y, p).
  Mat3 R;
  R.col(0) = Vec3::UnitZ();
  R.col(1) = Vec3::UnitX();
  R.col(2) = Vec3::UnitY();
  TMrptInverseDepth out;
  out.pose = poseFromRt(R, f.anchor_W);
  out.mean = Vec3(f.rho, f.theta, f.phi);
  // Permutation (theta, phi, rho) -> (rho, theta, phi): out = P in, cov = P C P^T.
  Mat3 P;
  P << 0, 0, 1,  //
      1, 0, 0,   //
      0, 1, 0;
  out.cov = P * f.cov_tpr * P.transpose();
  return out;
}

Mat3 mrptEllipsoidCovariance(const Mat3& C)
{
  if (!C.allFinite()) return Mat3::Zero();
  const Mat3 Cs = 0.5 * (C + C.transpose());
  Mat3 P = Mat3::Zero();  // axis reversal
  P(0, 2) = P(1, 1) = P(2, 0) = 1;
  const Eigen::LLT<Mat3> llt(P * Cs * P);
  if (llt.info() != Eigen::Success) return Mat3::Zero();
  const Mat3 L = llt.matrixL();
  if ((L.diagonal().array() <= 0).any()) return Mat3::Zero();
  const Mat3 Up = P * L * P;  // upper triangular, Up Up^T = C
  return Up.transpose() * Up;
}

mrpt::img::TColor toMrptColour(const TColour& c, std::uint8_t alpha)
{
  return mrpt::img::TColor(c.r, c.g, c.b, alpha);
}
}  // namespace immslam::viz
