/* imm-monoslam — Kannala-Brandt fisheye camera: projection, fold angle, Newton unprojection. */
#include <immslam/camera/CFisheyeCamera.h>

#include "camera_detail.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace immslam::camera
{
namespace
{
/** Points closer to the optical axis than this (sin theta) use the limit of the projection, the
 * pinhole (theta_d = theta + O(theta^3), the ratio theta_d / rho is then 1/z to rounding). */
constexpr double kAxisSin = 1e-9;
/** The largest angle: just short of 90 degrees (z > 0; detail::inFront needs z > 1e-9 |p|). */
const double kHalfPi = 0.5 * M_PI * (1 - 1e-9);

/** d(theta_d)/d(theta) as a function of t = theta^2. */
double angleSlope(double t, const double* k)
{
  return 1.0 + t * (3.0 * k[0] + t * (5.0 * k[1] + t * (7.0 * k[2] + t * 9.0 * k[3])));
}
}  // namespace

CFisheyeCamera::CFisheyeCamera(int width, int height, double fx, double fy, double cx, double cy, double k1,
                               double k2, double k3, double k4)
    : CCameraModel(width, height, fx, fy, cx, cy), m_k{k1, k2, k3, k4}
{
  const char* names[] = {"k1", "k2", "k3", "k4"};
  for (int i = 0; i < 4; ++i)
    if (!std::isfinite(m_k[i])) throw std::runtime_error(std::string("fisheye camera: ") + names[i] + " must be finite");
  // The first fold of the slope on [0, 90 deg]: a fine scan (the slope is a polynomial of degree 4 in
  // theta^2, at most 4 sign changes), then bisection to full precision.
  m_thetaMax = kHalfPi;
  constexpr int kSteps = 4096;
  double lo = 0;
  for (int i = 1; i <= kSteps; ++i)
  {
    const double hi = kHalfPi * i / kSteps;
    const double slope = angleSlope(hi * hi, m_k);
    if (!(slope > 0) || !std::isfinite(slope))
    {
      double a = lo, b = hi;
      for (int it = 0; it < 200 && b - a > 1e-16 * b; ++it)
      {
        const double mid = 0.5 * (a + b);
        const double sm = angleSlope(mid * mid, m_k);
        (sm > 0 && std::isfinite(sm) ? a : b) = mid;
      }
      m_thetaMax = a;
      break;
    }
    lo = hi;
  }
  if (!(m_thetaMax > 0))
    throw std::runtime_error("fisheye camera: the coefficients fold the projection at the optical axis");
  m_thetaDMax = distortAngle(m_thetaMax);
  if (!(std::isfinite(m_thetaDMax) && m_thetaDMax > 0))
    throw std::runtime_error("fisheye camera: the coefficients overflow the angle map");
}

std::vector<double> CFisheyeCamera::parameters() const { return {m_fx, m_fy, m_cx, m_cy, m_k[0], m_k[1], m_k[2], m_k[3]}; }

double CFisheyeCamera::distortAngle(double theta, double* dThetaD) const
{
  const double t = theta * theta;
  if (dThetaD) *dThetaD = angleSlope(t, m_k);
  return theta * (1.0 + t * (m_k[0] + t * (m_k[1] + t * (m_k[2] + t * m_k[3]))));
}

double CFisheyeCamera::undistortAngle(double thetaD, bool* clamped) const
{
  if (clamped) *clamped = false;
  if (!(thetaD > 0)) return 0.0;
  if (thetaD >= m_thetaDMax)
  {
    if (clamped) *clamped = true;
    return m_thetaMax * (1 - 1e-12);  // the ray at the limit, still projectable
  }
  // Newton kept inside the bracket [lo, hi] of the monotone branch.
  double lo = 0, hi = m_thetaMax, theta = std::min(thetaD, 0.5 * hi);
  for (int it = 0; it < 100; ++it)
  {
    double slope;
    const double err = distortAngle(theta, &slope) - thetaD;
    (err > 0 ? hi : lo) = theta;
    double next = theta - err / slope;
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    const bool done = std::abs(next - theta) <= 1e-15 * std::max(1.0, theta);
    theta = next;
    if (done) break;
  }
  return theta;
}

bool CFisheyeCamera::project(const Vec3& p_C, Vec2& uv, Mat23* J_uv_p) const
{
  if (!detail::inFront(p_C)) return false;
  const double x = p_C.x(), y = p_C.y(), z = p_C.z();
  const double rho2 = x * x + y * y, n2 = rho2 + z * z, rho = std::sqrt(rho2);
  if (rho <= kAxisSin * std::sqrt(n2))
  {
    // On the axis: the pinhole limit, exact to rounding.
    const double iz = 1.0 / z;
    uv << m_fx * x * iz + m_cx, m_fy * y * iz + m_cy;
    if (J_uv_p)
      *J_uv_p << m_fx * iz, 0, -m_fx * x * iz * iz,  //
          0, m_fy * iz, -m_fy * y * iz * iz;
    return true;
  }
  const double theta = std::atan2(rho, z);
  if (!(theta < m_thetaMax)) return false;
  double slope;
  const double thetaD = distortAngle(theta, &slope);
  const double s = thetaD / rho;  // (x', y') = s (x, y)
  uv << m_fx * s * x + m_cx, m_fy * s * y + m_cy;
  if (J_uv_p)
  {
    // Chain rule: d theta/dp = (z x / (rho n2), z y / (rho n2), -rho / n2), d rho/dp = (x, y, 0)/rho,
    // ds/dp = slope/rho d theta/dp - theta_d/rho^2 d rho/dp; d(s x, s y)/dp = s [I2 0] + (x, y)^T ds/dp.
    const Vec3 dTheta(z * x / (rho * n2), z * y / (rho * n2), -rho / n2);
    const Vec3 dRho(x / rho, y / rho, 0.0);
    const Vec3 ds = (slope / rho) * dTheta - (thetaD / rho2) * dRho;
    Mat23 J;
    J << s, 0, 0,  //
        0, s, 0;
    J.row(0) += x * ds.transpose();
    J.row(1) += y * ds.transpose();
    J.row(0) *= m_fx;
    J.row(1) *= m_fy;
    *J_uv_p = J;
  }
  return true;
}

math::Bearing CFisheyeCamera::unproject(const Vec2& uv, Mat32* J_b_uv) const
{
  const Vec2 c((uv.x() - m_cx) / m_fx, (uv.y() - m_cy) / m_fy);  // theta_d (cos phi, sin phi)
  const double thetaD = c.norm();
  if (thetaD <= kAxisSin)
  {
    Mat2 J_n_uv = Mat2::Zero();
    J_n_uv(0, 0) = 1.0 / m_fx;
    J_n_uv(1, 1) = 1.0 / m_fy;
    return detail::bearingOfNormalized(c, J_n_uv, J_b_uv);
  }
  bool clamped = false;
  const double theta = undistortAngle(thetaD, &clamped);
  const double sn = std::sin(theta), cs = std::cos(theta), q = sn / thetaD;
  const Vec3 b(q * c.x(), q * c.y(), cs);
  if (J_b_uv)
  {
    // b = (q c, cos theta), q = sin(theta)/theta_d, theta(theta_d) with d theta/d theta_d = 1/slope
    // (0 when clamped), d theta_d/dc = c^T/theta_d.
    double slope;
    distortAngle(theta, &slope);
    const double dTheta = clamped ? 0.0 : 1.0 / slope;
    const double dq = (cs * dTheta * thetaD - sn) / (thetaD * thetaD);
    const Eigen::RowVector2d dThetaD_dc = c.transpose() / thetaD;
    Mat32 J;
    J.topRows<2>() = q * Mat2::Identity() + c * (dq * dThetaD_dc);
    J.row(2) = -sn * dTheta * dThetaD_dc;
    J.col(0) /= m_fx;
    J.col(1) /= m_fy;
    *J_b_uv = J;
  }
  return math::Bearing(b);
}

CCameraModel::Ptr CFisheyeCamera::scaled(double s) const
{
  detail::checkScale(s, modelName());
  return std::make_shared<CFisheyeCamera>(detail::scaleSize(m_width, s), detail::scaleSize(m_height, s), s * m_fx,
                                          s * m_fy, detail::scalePixel(m_cx, s), detail::scalePixel(m_cy, s), m_k[0],
                                          m_k[1], m_k[2], m_k[3]);
}
}  // namespace immslam::camera
