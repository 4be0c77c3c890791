/* imm-monoslam — feature patches: stored region and warped (predicted) templates. */
#include <immslam/frontend/frontend.h>

#include <Eigen/LU>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace immslam::frontend
{
namespace
{
/** Singular values of the warp are clamped to this range (see predictTemplate). */
constexpr double kMinWarpScale = 0.25;
constexpr double kMaxWarpScale = 4.0;

/** A^{-1} with A's singular values clamped to [kMinWarpScale, kMaxWarpScale]; identity if A is not
 * finite. */
Mat2 saturatedInverse(const Mat2& A)
{
  if (!A.allFinite()) return Mat2::Identity();
  const double det = A.determinant();
  // Fast path: a well-conditioned A inside the range needs no SVD. The singular values of a 2x2
  // are s1,2 = sqrt((f +- sqrt(f^2 - 4 det^2)) / 2) with f = |A|_F^2.
  const double f = A.squaredNorm();
  const double disc = std::sqrt(std::max(f * f - 4 * det * det, 0.0));
  const double s1 = std::sqrt(0.5 * (f + disc)), s2 = std::sqrt(std::max(0.5 * (f - disc), 0.0));
  if (s2 >= kMinWarpScale && s1 <= kMaxWarpScale) return A.inverse();
  Eigen::JacobiSVD<Mat2> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Vec2 sv = svd.singularValues();
  for (int i = 0; i < 2; ++i) sv[i] = std::clamp(sv[i], kMinWarpScale, kMaxWarpScale);
  // A = U diag(s) V^T  =>  A^{-1} = V diag(1/s) U^T
  return svd.matrixV() * sv.cwiseInverse().asDiagonal() * svd.matrixU().transpose();
}
}  // namespace

bool CFeaturePatch::extract(const cv::Mat& grey, const Vec2& uv, int halfSize)
{
  if (grey.empty() || grey.type() != CV_8UC1)
    throw std::runtime_error("frontend::CFeaturePatch::extract: expected a CV_8UC1 image");
  if (halfSize < 1) throw std::runtime_error("frontend::CFeaturePatch::extract: halfSize < 1");
  if (!uv.allFinite()) return false;
  const int rh = 2 * halfSize + 1;
  const long cu = std::lround(uv.x()), cv_ = std::lround(uv.y());
  if (cu - rh < 0 || cv_ - rh < 0 || cu + rh >= grey.cols || cv_ + rh >= grey.rows) return false;
  // A fresh buffer: copies of this patch share the old one (cv::Mat semantics) and must not change.
  cv::Mat region;
  grey(cv::Rect(int(cu - rh), int(cv_ - rh), 2 * rh + 1, 2 * rh + 1)).convertTo(region, CV_32F);
  m_region = region;
  m_subpixel = uv - Vec2(double(cu), double(cv_));
  m_half = halfSize;
  m_regionHalf = rh;
  return true;
}

cv::Mat CFeaturePatch::predictTemplate(const Mat2& A) const
{
  cv::Mat out;
  predictTemplate(A, out);
  return out;
}

void CFeaturePatch::predictTemplate(const Mat2& A, cv::Mat& out) const
{
  if (!valid()) throw std::runtime_error("frontend::CFeaturePatch::predictTemplate: empty patch");
  const Mat2 Ainv = saturatedInverse(A);
  const int n = 2 * m_half + 1;
  out.create(n, n, CV_32F);

  const int last = m_region.cols - 1;  // region is square
  const double maxc = double(last);
  // Region coordinates of the feature (sub-pixel) and of the template's top-left pixel.
  const double cu = m_regionHalf + m_subpixel.x(), cv_ = m_regionHalf + m_subpixel.y();
  const double a = Ainv(0, 0), b = Ainv(0, 1), c = Ainv(1, 0), d = Ainv(1, 1);
  for (int ty = 0; ty < n; ++ty)
  {
    const double dy = ty - m_half;
    float* o = out.ptr<float>(ty);
    for (int tx = 0; tx < n; ++tx)
    {
      const double dx = tx - m_half;
      // Region offset A^{-1} d of template offset d, clamped to the region (border replicate).
      const double qx = std::clamp(cu + a * dx + b * dy, 0.0, maxc);
      const double qy = std::clamp(cv_ + c * dx + d * dy, 0.0, maxc);
      const int x0 = std::min(int(qx), last - 1), y0 = std::min(int(qy), last - 1);
      const float fx = float(qx - x0), fy = float(qy - y0);
      const float* r0 = m_region.ptr<float>(y0) + x0;
      const float* r1 = m_region.ptr<float>(y0 + 1) + x0;
      const float top = r0[0] + fx * (r0[1] - r0[0]);
      const float bot = r1[0] + fx * (r1[1] - r1[0]);
      o[tx] = top + fy * (bot - top);
    }
  }
}
}  // namespace immslam::frontend
