/* imm-monoslam — relocalisation: map templates matched at the image's corners, RANSAC PnP. */
#include <immslam/frontend/frontend.h>
#include <immslam/math/quaternion.h>
#include <immslam/tracking/relocalise.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace immslam::slam
{
namespace
{
/** Makes v zero-mean and of unit norm in place; empties it if it is flat (no ZNCC defined). */
void normalizeZeroMean(std::vector<float>& v)
{
  double mean = 0;
  for (float a : v) mean += a;
  mean /= static_cast<double>(v.size());
  double ss = 0;
  for (float& a : v)
  {
    a = static_cast<float>(a - mean);
    ss += static_cast<double>(a) * a;
  }
  if (!(ss > 1e-6 * v.size()))
  {
    v.clear();
    return;
  }
  const float s = static_cast<float>(1.0 / std::sqrt(ss));
  for (float& a : v) a *= s;
}

/** Zero-mean, unit-norm copy of a template (empty if it is flat). */
std::vector<float> normalizedTemplate(const cv::Mat& t32)
{
  std::vector<float> out(t32.begin<float>(), t32.end<float>());
  normalizeZeroMean(out);
  return out;
}

/** Zero-mean, unit-norm image window of the template's size centred at (u, v) (empty if flat). */
std::vector<float> normalizedWindow(const cv::Mat& grey, int u, int v, int half)
{
  const int side = 2 * half + 1;
  std::vector<float> out(static_cast<std::size_t>(side * side));
  for (int y = 0; y < side; ++y)
  {
    const std::uint8_t* row = grey.ptr<std::uint8_t>(v - half + y) + (u - half);
    for (int x = 0; x < side; ++x) out[static_cast<std::size_t>(y * side + x)] = row[x];
  }
  normalizeZeroMean(out);
  return out;
}
/** Corners of the whole image, strongest first, where a template of half size `half` fits (and the
 * valid mask allows), at most p.maxCorners. */
std::vector<cv::KeyPoint> relocalisationCorners(const cv::Mat& grey, int half, const TRelocaliseParams& p)
{
  std::vector<cv::KeyPoint> kps;
  cv::FAST(grey, kps, p.fastThreshold, true);
  kps.erase(std::remove_if(kps.begin(), kps.end(),
                           [&](const cv::KeyPoint& k) {
                             const int u = cvRound(k.pt.x), v = cvRound(k.pt.y);
                             return u < half + 1 || v < half + 1 || u >= grey.cols - half - 1 || v >= grey.rows - half - 1 ||
                                    (!p.validMask.empty() && p.validMask.size() == grey.size() &&
                                     !p.validMask.at<std::uint8_t>(v, u));
                           }),
            kps.end());
  std::stable_sort(kps.begin(), kps.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
  if (static_cast<int>(kps.size()) > p.maxCorners) kps.resize(static_cast<std::size_t>(p.maxCorners));
  return kps;
}

/** 2D-3D correspondences: the map points, their normalized image coordinates, which point, the pixel. */
struct TCorrespondences
{
  std::vector<cv::Point3d> obj;
  std::vector<cv::Point2d> img;
  std::vector<int> which;
  std::vector<Vec2> uv;
};

/** A point's best corner by ZNCC over its usable templates, unless ambiguous. \return the corner's
 * index (-1: none) and, in bestT, the template that scored. */
int bestCorner(const std::vector<cv::KeyPoint>& kps, const std::vector<std::vector<float>>& windows,
               const std::vector<std::vector<float>>& Ts, const TRelocaliseParams& p, int& bestT)
{
  double best = -1, second = -1;
  int bestC = -1;
  bestT = 0;
  for (std::size_t c = 0; c < kps.size(); ++c)
  {
    const auto& W = windows[c];
    if (W.empty()) continue;
    float s = -1;
    int tOf = 0;
    for (std::size_t j = 0; j < Ts.size(); ++j)
    {
      float sj = 0;
      for (std::size_t i = 0; i < W.size(); ++i) sj += Ts[j][i] * W[i];
      if (sj > s)
      {
        s = sj;
        tOf = static_cast<int>(j);
      }
    }
    if (s > best)
    {
      // The previous best becomes the second unless it is the same spot.
      if (bestC >= 0 && cv::norm(kps[c].pt - kps[static_cast<std::size_t>(bestC)].pt) > 3.0) second = std::max(second, best);
      best = s;
      bestC = static_cast<int>(c);
      bestT = tOf;
    }
    else if (bestC >= 0 && s > second && cv::norm(kps[c].pt - kps[static_cast<std::size_t>(bestC)].pt) > 3.0)
      second = s;
  }
  if (bestC < 0 || best < p.minNcc || best - second < p.ambiguityMargin) return -1;
  return bestC;
}

/** Each point's best corner by ZNCC, refined to sub-pixel by the active search's own routine. */
TCorrespondences matchPoints(const cv::Mat& grey, const camera::CCameraModel& cam, const std::vector<TRelocPoint>& points,
                             const std::vector<cv::KeyPoint>& kps, int half, const TRelocaliseParams& p)
{
  std::vector<std::vector<float>> windows(kps.size());
  for (std::size_t c = 0; c < kps.size(); ++c)
    windows[c] = normalizedWindow(grey, cvRound(kps[c].pt.x), cvRound(kps[c].pt.y), half);
  TCorrespondences out;
  frontend::TSearchParams sp;
  sp.minScore = p.minNcc;
  const Mat2 S = Mat2::Identity() * 0.75;  // gate radius ~2.1 px around the corner
  for (int k = 0; k < static_cast<int>(points.size()); ++k)
  {
    const TRelocPoint& pt = points[k];
    std::vector<std::vector<float>> Ts;
    std::vector<const cv::Mat*> T32;
    for (const cv::Mat& t : pt.templates)
    {
      if (t.type() != CV_32FC1 || t.cols != 2 * half + 1 || t.rows != 2 * half + 1) continue;
      auto T = normalizedTemplate(t);
      if (T.empty()) continue;
      Ts.push_back(std::move(T));
      T32.push_back(&t);
    }
    if (Ts.empty()) continue;
    int bestT = 0;
    const int bestC = bestCorner(kps, windows, Ts, p, bestT);
    if (bestC < 0) continue;
    const cv::Mat& t32 = *T32[static_cast<std::size_t>(bestT)];
    const Vec2 h(kps[static_cast<std::size_t>(bestC)].pt.x, kps[static_cast<std::size_t>(bestC)].pt.y);
    const auto res = frontend::searchInEllipse(grey, t32, h, S, sp);
    if (!res.found) continue;
    const Vec3 b = cam.unproject(res.uv).unitVector();
    if (!(b.z() > 1e-3)) continue;
    out.obj.emplace_back(pt.p_W.x(), pt.p_W.y(), pt.p_W.z());
    out.img.emplace_back(b.x() / b.z(), b.y() / b.z());
    out.which.push_back(k);
    out.uv.push_back(res.uv);
  }
  return out;
}

/** RANSAC PnP on the correspondences, refined on its inliers (Levenberg-Marquardt); fills the pose,
 * the inliers and their median depth of `out` (ok when at least p.minInliers remain). */
void solvePose(const TCorrespondences& m, const std::vector<TRelocPoint>& points, double focal,
               const TRelocaliseParams& p, TRelocalisation& out)
{
  cv::Mat rvec, tvec;
  std::vector<int> inl;
  const cv::Mat K = cv::Mat::eye(3, 3, CV_64F);
  bool solved = false;
  try
  {
    solved = cv::solvePnPRansac(m.obj, m.img, K, cv::noArray(), rvec, tvec, false, p.ransacIterations,
                                static_cast<float>(p.reprojectionPx / focal), 0.999, inl, cv::SOLVEPNP_EPNP);
  }
  catch (const cv::Exception&)
  {
    solved = false;  // degenerate configuration (e.g. all points on a line): no relocalisation
  }
  if (!solved || static_cast<int>(inl.size()) < p.minInliers) return;
  // Refine on the inliers (Levenberg-Marquardt from the RANSAC pose) and recount them.
  std::vector<cv::Point3d> o2;
  std::vector<cv::Point2d> i2;
  for (int i : inl)
  {
    o2.push_back(m.obj[static_cast<std::size_t>(i)]);
    i2.push_back(m.img[static_cast<std::size_t>(i)]);
  }
  cv::solvePnP(o2, i2, K, cv::noArray(), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
  const Vec3 w(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2));
  const Vec3 t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  if (!w.allFinite() || !t.allFinite()) return;
  const Vec4 q = math::quatFromRotationVector(w);
  const Mat3 R = math::quatToRotation(q);
  const double gate = p.reprojectionPx / focal;
  std::vector<double> depths;
  for (std::size_t a = 0; a < m.obj.size(); ++a)
  {
    const Vec3 pc = R * Vec3(m.obj[a].x, m.obj[a].y, m.obj[a].z) + t;
    if (!(pc.z() > 0)) continue;
    const double ex = pc.x() / pc.z() - m.img[a].x, ey = pc.y() / pc.z() - m.img[a].y;
    if (std::hypot(ex, ey) > gate) continue;
    out.inlierIds.push_back(points[static_cast<std::size_t>(m.which[a])].id);
    out.inlierUv.push_back(m.uv[a]);
    depths.push_back(pc.norm());
  }
  if (static_cast<int>(out.inlierIds.size()) < p.minInliers) return;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  out.medianDepth = depths[depths.size() / 2];
  out.r_CW = t;
  out.q_CW = q;
  out.ok = true;
}
}  // namespace

TRelocalisation relocalise(const cv::Mat& grey, const camera::CCameraModel& cam, const std::vector<TRelocPoint>& points,
                           const TRelocaliseParams& p)
{
  if (grey.empty() || grey.type() != CV_8UC1) throw std::runtime_error("relocalise: needs a non-empty 8-bit grey image");
  TRelocalisation out;
  if (points.empty() || static_cast<int>(points.size()) < std::max(p.minInliers, 4)) return out;
  const int half = points.front().templates.empty() ? 0 : points.front().templates.front().cols / 2;
  if (half < 1) return out;
  const std::vector<cv::KeyPoint> kps = relocalisationCorners(grey, half, p);
  out.nCorners = static_cast<int>(kps.size());
  const TCorrespondences m = matchPoints(grey, cam, points, kps, half, p);
  out.nCorrespondences = static_cast<int>(m.obj.size());
  if (out.nCorrespondences < std::max(p.minInliers, 4)) return out;
  solvePose(m, points, 0.5 * (cam.fx() + cam.fy()), p, out);
  return out;
}
}  // namespace immslam::slam
