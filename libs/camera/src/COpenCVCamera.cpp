/* imm-monoslam — OpenCV radial-tangential camera: projection, fold radius, Newton unprojection. */
#include <immslam/camera/COpenCVCamera.h>

#include "camera_detail.h"

#include <algorithm>
#include <array>
#include <utility>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace immslam::camera
{
namespace
{
constexpr double kInf = std::numeric_limits<double>::infinity();
/** Largest r^2 searched for a fold (r = 1e6: 6e-5 degrees short of 90). */
constexpr double kS2Max = 1e12;

/** d(r_d)/d(r) of the radial map r -> r (1 + k1 r^2 + k2 r^4 + k3 r^6), as a function of s = r^2. */
double radialSlope(double s, double k1, double k2, double k3)
{
  return 1.0 + s * (3.0 * k1 + s * (5.0 * k2 + s * 7.0 * k3));
}

/** The first s = r^2 > 0 where radialSlope() reaches 0, +inf if none. The cubic is split at the
 * roots of its derivative into monotone pieces; the first piece whose end is <= 0 holds the root,
 * found by bisection. */
double foldRadius2(double k1, double k2, double k3)
{
  std::array<double, 3> ends{};
  int n = 0;
  auto addCritical = [&](double s) {
    if (s > 0 && s < kS2Max && std::isfinite(s)) ends[n++] = s;
  };
  // Derivative of the slope in s: 3 k1 + 10 k2 s + 21 k3 s^2.
  const double a = 21.0 * k3, b = 10.0 * k2, c = 3.0 * k1;
  if (a != 0)
  {
    const double disc = b * b - 4 * a * c;
    if (disc >= 0)
    {
      // Numerically stable roots of a s^2 + b s + c.
      const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
      if (q != 0)
      {
        addCritical(q / a);
        addCritical(c / q);
      }
      else
        addCritical(0.0);
    }
  }
  else if (b != 0)
    addCritical(-c / b);
  if (n == 2 && ends[1] < ends[0]) std::swap(ends[0], ends[1]);
  ends[n++] = kS2Max;

  double lo = 0;
  for (int i = 0; i < n; ++i)
  {
    double hi = ends[i];
    if (radialSlope(hi, k1, k2, k3) <= 0)
    {
      // Slope > 0 at lo, <= 0 at hi, monotone in between: bisect to full precision.
      for (int it = 0; it < 200 && hi - lo > 1e-16 * hi; ++it)
      {
        const double mid = 0.5 * (lo + hi);
        (radialSlope(mid, k1, k2, k3) > 0 ? lo : hi) = mid;
      }
      return lo;
    }
    lo = hi;
  }
  // No fold up to r = 1e6: monotone for good unless the leading coefficient is negative.
  const double lead = k3 != 0 ? k3 : (k2 != 0 ? k2 : k1);
  return lead < 0 ? kS2Max : kInf;
}
}  // namespace

COpenCVCamera::COpenCVCamera(int width, int height, double fx, double fy, double cx, double cy,
    double k1, double k2, double p1, double p2, double k3)
    : CCameraModel(width, height, fx, fy, cx, cy), m_k1(k1), m_k2(k2), m_p1(p1), m_p2(p2), m_k3(k3)
{
  const char* names[] = {"k1", "k2", "p1", "p2", "k3"};
  const double vals[] = {k1, k2, p1, p2, k3};
  for (int i = 0; i < 5; ++i)
    if (!std::isfinite(vals[i]))
      throw std::runtime_error(std::string("opencv camera: ") + names[i] + " must be finite");
  m_r2Max = foldRadius2(k1, k2, k3);
  m_rMax = std::sqrt(m_r2Max);
}

std::vector<double> COpenCVCamera::parameters() const
{
  return {m_fx, m_fy, m_cx, m_cy, m_k1, m_k2, m_p1, m_p2, m_k3};
}

Vec2 COpenCVCamera::distort(const Vec2& n, Mat2* J_d_n) const
{
  const double x = n.x(), y = n.y();
  const double x2 = x * x, y2 = y * y, xy = x * y, r2 = x2 + y2;
  const double radial = 1.0 + r2 * (m_k1 + r2 * (m_k2 + r2 * m_k3));
  const Vec2 d(x * radial + 2.0 * m_p1 * xy + m_p2 * (r2 + 2.0 * x2),
      y * radial + m_p1 * (r2 + 2.0 * y2) + 2.0 * m_p2 * xy);
  if (J_d_n)
  {
    // d(radial)/d(r2), and d(r2)/dx = 2x, d(r2)/dy = 2y.
    const double dR = m_k1 + r2 * (2.0 * m_k2 + 3.0 * m_k3 * r2);
    const double off = 2.0 * xy * dR + 2.0 * m_p1 * x + 2.0 * m_p2 * y;
    (*J_d_n) << radial + 2.0 * x2 * dR + 2.0 * m_p1 * y + 6.0 * m_p2 * x, off,  //
        off, radial + 2.0 * y2 * dR + 6.0 * m_p1 * y + 2.0 * m_p2 * x;
  }
  return d;
}

bool COpenCVCamera::project(const Vec3& p_C, Vec2& uv, Mat23* J_uv_p) const
{
  if (!detail::inFront(p_C)) return false;
  const Vec2 n(p_C.x() / p_C.z(), p_C.y() / p_C.z());
  if (!(n.squaredNorm() < m_r2Max)) return false;  // beyond the fold: the model is not valid
  if (!J_uv_p)
  {
    const Vec2 d = distort(n);
    uv << m_fx * d.x() + m_cx, m_fy * d.y() + m_cy;
    return true;
  }
  Mat2 J_d_n;
  const Vec2 d = distort(n, &J_d_n);
  uv << m_fx * d.x() + m_cx, m_fy * d.y() + m_cy;
  Mat23 J_n_p;
  detail::normalizedJacobian(p_C, J_n_p);
  // Chain rule: d(uv)/d(p) = diag(fx, fy) * d(distorted)/d(normalized) * d(normalized)/d(p).
  const Mat23 J_d_p = J_d_n * J_n_p;
  J_uv_p->row(0) = m_fx * J_d_p.row(0);
  J_uv_p->row(1) = m_fy * J_d_p.row(1);
  return true;
}

Vec2 COpenCVCamera::undistort(const Vec2& nd) const
{
  const double rd = nd.norm();
  if (!(rd > 0)) return Vec2::Zero();
  const auto radialMap = [this](double r) {
    const double s = r * r;
    return r * (1.0 + s * (m_k1 + s * (m_k2 + s * m_k3)));
  };

  // 1) Radial part alone, r * R(r^2) = rd, by Newton kept inside a bracket [lo, hi] of the
  //    monotone branch: a start inside the valid domain for the full 2-D problem.
  double lo = 0, hi;
  if (std::isfinite(m_rMax))
    hi = m_rMax;
  else
  {
    hi = std::max(rd, 1.0);
    for (int it = 0; it < 200 && radialMap(hi) < rd; ++it) hi *= 2;
  }
  double r;
  if (radialMap(hi) <= rd)
    r = hi * (1 - 1e-12);  // beyond the largest radius the model produces: the fold ray
  else
  {
    r = std::min(rd, 0.5 * hi);
    for (int it = 0; it < 100; ++it)
    {
      const double err = radialMap(r) - rd;
      (err > 0 ? hi : lo) = r;
      double rn = r - err / radialSlope(r * r, m_k1, m_k2, m_k3);
      if (!(rn > lo && rn < hi)) rn = 0.5 * (lo + hi);
      const bool done = std::abs(rn - r) <= 1e-12 * std::max(1.0, r);  // step 2 polishes
      r = rn;
      if (done) break;
    }
  }
  Vec2 n = nd * (r / rd);

  // 2) Newton on the full model with its analytic 2x2 Jacobian (quadratic convergence).
  for (int it = 0; it < 30; ++it)
  {
    Mat2 J;
    const Vec2 e = distort(n, &J) - nd;
    const double det = J(0, 0) * J(1, 1) - J(0, 1) * J(1, 0);
    if (!(std::abs(det) > 1e-300)) break;
    const Vec2 step((J(1, 1) * e.x() - J(0, 1) * e.y()) / det, (J(0, 0) * e.y() - J(1, 0) * e.x()) / det);
    n -= step;
    const double n2 = n.squaredNorm();
    if (!(n2 < m_r2Max)) n *= m_rMax * (1 - 1e-12) / std::sqrt(n2);  // stay on the valid branch
    // Quadratic convergence: after a step this small the error is ~1e-28, below rounding.
    if (step.norm() <= 1e-14 * (1.0 + n.norm())) break;
  }
  return n;
}

math::Bearing COpenCVCamera::unproject(const Vec2& uv, Mat32* J_b_uv) const
{
  const Vec2 nd((uv.x() - m_cx) / m_fx, (uv.y() - m_cy) / m_fy);
  const Vec2 n = undistort(nd);
  Mat2 J_n_uv = Mat2::Zero();
  if (J_b_uv)
  {
    // Implicit function: d(n)/d(nd) = inverse of the distortion Jacobian at the solution.
    Mat2 J_d_n;
    distort(n, &J_d_n);
    const double det = J_d_n(0, 0) * J_d_n(1, 1) - J_d_n(0, 1) * J_d_n(1, 0);
    Mat2 J_n_nd;
    J_n_nd << J_d_n(1, 1) / det, -J_d_n(0, 1) / det, -J_d_n(1, 0) / det, J_d_n(0, 0) / det;
    J_n_uv.col(0) = J_n_nd.col(0) / m_fx;
    J_n_uv.col(1) = J_n_nd.col(1) / m_fy;
  }
  return detail::bearingOfNormalized(n, J_n_uv, J_b_uv);
}

CCameraModel::Ptr COpenCVCamera::scaled(double s) const
{
  detail::checkScale(s, modelName());
  return std::make_shared<COpenCVCamera>(detail::scaleSize(m_width, s),
      detail::scaleSize(m_height, s), s * m_fx, s * m_fy, detail::scalePixel(m_cx, s),
      detail::scalePixel(m_cy, s), m_k1, m_k2, m_p1, m_p2, m_k3);
}
}  // namespace immslam::camera
