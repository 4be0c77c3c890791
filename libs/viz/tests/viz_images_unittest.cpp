/* Tests: overlay geometry (drawn ellipses are the gate ellipses), colours, conversion of inputs,
 * the overlay writer. */
#include <gtest/gtest.h>
#include <immslam/viz/COverlayWriter.h>
#include <immslam/viz/overlay.h>

#include <Eigen/Dense>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cmath>
#include <filesystem>
#include <random>

using namespace immslam;
using namespace immslam::viz;

namespace
{
std::string outDir()
{
  const std::string d = std::string(IMMSLAM_BINARY_DIR) + "/viz_test_output";
  std::filesystem::create_directories(d);
  return d;
}


double distanceToPolygon(const Vec2& p, const std::vector<Vec2>& poly)
{
  double best = 1e300;
  for (size_t i = 0; i < poly.size(); ++i)
  {
    const Vec2 a = poly[i], b = poly[(i + 1) % poly.size()];
    const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * (b - a) - p).norm());
  }
  return best;
}

/** Pixels whose colour is close to `c` (each channel within tol). */
std::vector<Vec2> pixelsOfColour(const cv::Mat& img, const TColour& c, int tol)
{
  std::vector<Vec2> out;
  for (int r = 0; r < img.rows; ++r)
    for (int col = 0; col < img.cols; ++col)
    {
      const cv::Vec3b p = img.at<cv::Vec3b>(r, col);
      if (std::abs(p[0] - c.b) <= tol && std::abs(p[1] - c.g) <= tol && std::abs(p[2] - c.r) <= tol)
        out.emplace_back(col, r);
    }
  return out;
}

TOverlayStyle bareStyle(int upscale)
{
  TOverlayStyle st;
  st.upscale = upscale;
  st.drawLegend = false;
  st.drawMatchLines = false;
  return st;
}
}  // namespace

TEST(VizOverlay, GatePolygonLiesOnTheGate)
{
  std::mt19937 rng(5);
  std::normal_distribution<double> n;
  for (int t = 0; t < 20; ++t)
  {
    Mat2 A;
    A << n(rng), n(rng), n(rng), n(rng);
    const Mat2 S = 20 * (A * A.transpose() + 0.1 * Mat2::Identity());
    const Vec2 h(100 + 10 * n(rng), 80 + 10 * n(rng));
    const double chi2 = 5.991;
    const auto poly = gateEllipsePolygon(h, S, chi2, 50);
    ASSERT_EQ(poly.size(), 50u);
    for (const auto& x : poly) EXPECT_NEAR((x - h).dot(S.inverse() * (x - h)), chi2, 1e-9);
    EXPECT_NEAR(gateEllipseArea(S, chi2), M_PI * chi2 * std::sqrt(S.determinant()), 1e-9);
  }
  EXPECT_TRUE(gateEllipsePolygon(Vec2(0, 0), -Mat2::Identity(), 5.991).empty());
  EXPECT_TRUE(gateEllipsePolygon(Vec2(0, 0), Mat2::Identity(), 0.0).empty());
}

TEST(VizOverlay, DrawnEllipseFollowsTheGate)
{
  Mat2 S;
  S << 90, 35, 35, 40;
  const Vec2 h(81.3, 62.7);
  const double chi2 = 5.991;
  for (int scale : {1, 2})
  {
    TOverlayContent c;
    TSearchView sv;
    sv.h = h;
    sv.S = S;
    sv.gateChi2 = chi2;
    sv.status = ESearchStatus::Inlier;
    c.searches.push_back(sv);
    const TOverlayStyle st = bareStyle(scale);
    const cv::Mat img = drawOverlay(cv::Mat(120, 160, CV_8UC3, cv::Scalar(0, 0, 0)), c, st);
    ASSERT_EQ(img.cols, 160 * scale);
    std::vector<Vec2> ideal;
    for (const auto& p : gateEllipsePolygon(h, S, chi2, 400)) ideal.push_back(toOverlayPixel(p, scale));
    const Vec2 hc = toOverlayPixel(h, scale);
    // Strongly coloured pixels (anti-aliasing blends the rest) lie on the ideal ellipse ...
    int n = 0;
    for (const Vec2& p : pixelsOfColour(img, st.inlierColour, 90))
    {
      if ((p - hc).norm() < st.markerRadius + 2) continue;  // the prediction's cross
      ++n;
      EXPECT_LT(distanceToPolygon(p, ideal), 1.0) << "scale " << scale << " pixel " << p.transpose();
    }
    EXPECT_GT(n, 40 * scale);
    // ... and the whole ellipse is drawn.
    const auto drawn = pixelsOfColour(img, st.inlierColour, 140);
    for (size_t i = 0; i < ideal.size(); i += 10)
    {
      double best = 1e9;
      for (const auto& p : drawn) best = std::min(best, (p - ideal[i]).norm());
      EXPECT_LT(best, 1.0) << "ellipse point " << ideal[i].transpose();
    }
  }
}

TEST(VizOverlay, ColoursAreDistinct)
{
  const TOverlayStyle st;
  const std::vector<TColour> cls{st.staticColour, st.dynamicColour, st.pendingColour};
  const std::vector<TColour> all{st.staticColour, st.dynamicColour, st.pendingColour,
      st.inlierColour, st.rescuedColour, st.rejectedColour, st.notFoundColour};
  for (size_t i = 0; i < all.size(); ++i)
    for (size_t j = i + 1; j < all.size(); ++j)
    {
      const double d = std::sqrt(std::pow(all[i].r - all[j].r, 2) +
          std::pow(all[i].g - all[j].g, 2) + std::pow(all[i].b - all[j].b, 2));
      EXPECT_GT(d, 80) << i << " vs " << j;
    }
  // MonoSLAMBOT Fig. 4: static blue, dynamic green, pending red.
  EXPECT_GT(cls[0].b, std::max(cls[0].r, cls[0].g));
  EXPECT_GT(cls[1].g, std::max(cls[1].r, cls[1].b));
  EXPECT_GT(cls[2].r, std::max(cls[2].g, cls[2].b));
}

TEST(VizOverlay, GreyInputIsConvertedAndUpscaledAndNotModified)
{
  cv::Mat grey(240, 320, CV_8UC1);
  cv::randu(grey, 0, 255);
  const cv::Mat before = grey.clone();
  TOverlayContent c;
  c.textLines = {"frame 12", "mu stationary 0.93"};
  TFeatureView f;
  f.uv = Vec2(100, 50);
  f.cls = EFeatureClass::Dynamic;
  c.features.push_back(f);
  const cv::Mat out = drawOverlay(grey, c);
  EXPECT_EQ(out.type(), CV_8UC3);
  EXPECT_EQ(out.cols, 640);  // 320x240 -> 2x by default
  EXPECT_EQ(out.rows, 480);
  EXPECT_EQ(cv::norm(grey, before, cv::NORM_INF), 0.0);
  // The marker centre has the dynamic colour.
  const Vec2 p = toOverlayPixel(f.uv, 2);
  const cv::Vec3b v = out.at<cv::Vec3b>(int(std::lround(p.y())), int(std::lround(p.x())));
  EXPECT_EQ(v, cv::Vec3b(palette::kDynamic.b, palette::kDynamic.g, palette::kDynamic.r));
  // Big images are not upscaled; 16-bit input is accepted.
  EXPECT_EQ(drawOverlay(cv::Mat(480, 640, CV_16UC1, cv::Scalar(30000)), c).cols, 640);
  EXPECT_THROW(drawOverlay(cv::Mat(), c), std::runtime_error);
}

TEST(VizOverlay, ExampleFigure)
{
  // A readable example (kept in the test output folder): a textured 320x240 frame with every
  // status and class.
  cv::Mat img(240, 320, CV_8UC1);
  for (int r = 0; r < img.rows; ++r)
    for (int col = 0; col < img.cols; ++col)
      img.at<uint8_t>(r, col) = static_cast<uint8_t>(
          90 + 60 * std::sin(col * 0.11) * std::cos(r * 0.07) + 30 * ((col / 16 + r / 16) % 2));
  TOverlayContent c;
  const ESearchStatus st[4] = {ESearchStatus::Inlier, ESearchStatus::Rescued,
      ESearchStatus::Rejected, ESearchStatus::NotFound};
  for (int i = 0; i < 8; ++i)
  {
    TSearchView s;
    s.h = Vec2(60 + 30 * i, 60 + 12 * (i % 3));
    s.S << 25 + 10 * i, 6 * (i % 3 - 1), 6 * (i % 3 - 1), 15 + 4 * i;
    s.status = st[i % 4];
    s.id = i;
    if (s.status != ESearchStatus::NotFound) s.z = s.h + Vec2(2.5 - i % 3, 1.5);
    c.searches.push_back(s);
  }
  const EFeatureClass cls[3] = {EFeatureClass::Static, EFeatureClass::Dynamic, EFeatureClass::Pending};
  for (int i = 0; i < 9; ++i) c.features.push_back({Vec2(40 + 30 * i, 170 + 10 * (i % 2)), cls[i % 3], 100 + i});
  c.textLines = {"frame 120   28.4 fps", "mu: stationary 0.91  rotation 0.07"};
  const cv::Mat out = drawOverlay(img, c);
  EXPECT_EQ(out.size(), cv::Size(640, 480));
  EXPECT_TRUE(cv::imwrite(outDir() + "/overlay_example.png", out));
}

TEST(VizOverlay, WriterWritesEveryNthFrameAndVideo)
{
  const std::string dir = outDir() + "/overlays";
  std::filesystem::remove_all(dir);
  const std::string video = outDir() + "/overlays.avi";
  std::filesystem::remove(video);
  {
    COverlayWriter w({dir, video, 2, 10.0, "frame_%06d.png"});
    for (long k = 0; k < 5; ++k)
    {
      cv::Mat img(48, 64, CV_8UC3, cv::Scalar(10 * k, 50, 200));
      EXPECT_EQ(w.write(k, img), k % 2 == 0);
    }
    EXPECT_EQ(w.framesWritten(), 3);
    EXPECT_EQ(w.pngPath(4), (std::filesystem::path(dir) / "frame_000004.png").string());
  }
  for (long k = 0; k < 5; ++k)
    EXPECT_EQ(std::filesystem::exists(dir + "/frame_00000" + std::to_string(k) + ".png"), k % 2 == 0);
  ASSERT_TRUE(std::filesystem::exists(video));
  EXPECT_GT(std::filesystem::file_size(video), 0u);
  cv::VideoCapture cap(video);
  if (cap.isOpened())
  {
    int n = 0;
    cv::Mat f;
    while (cap.read(f)) ++n;
    EXPECT_EQ(n, 3);
  }
  EXPECT_THROW(COverlayWriter({dir, "", 0}), std::runtime_error);
  EXPECT_THROW(COverlayWriter({dir, "", 1, 10.0, "frame.png"}), std::runtime_error);
  EXPECT_THROW(COverlayWriter({dir, "", 1, 10.0, "%s_%d.png"}), std::runtime_error);
}
