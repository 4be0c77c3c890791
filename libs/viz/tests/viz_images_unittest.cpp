/* Tests: overlay geometry (drawn ellipses are the gate ellipses), colours, conversion of inputs,
 * the overlay writer, and the plots (written, sized, deterministic). */
#include <gtest/gtest.h>
#include <immslam/viz/COverlayWriter.h>
#include <immslam/viz/CPlot.h>
#include <immslam/viz/overlay.h>
#include <immslam/viz/plots.h>

#include <Eigen/Dense>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
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

std::string readBytes(const std::string& path)
{
  std::ifstream f(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
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
  writePng(out, outDir() + "/overlay_example.png");
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

namespace
{
/** A synthetic IMM run: stationary, then rotating, then translating, with switching spikes. */
void syntheticProbabilities(std::vector<double>& t, std::vector<std::string>& names, MatX& P,
    std::vector<std::string>& truth)
{
  names = {"stationary", "rotation_0.1px", "rotation_0.5px", "rotation_1px", "general_0.1px",
      "general_0.5px", "general_1px"};
  const int T = 300;
  P.resize(T, 7);
  t.clear();
  truth.clear();
  for (int i = 0; i < T; ++i)
  {
    t.push_back(i / 30.0);
    Eigen::Matrix<double, 7, 1> w = Eigen::Matrix<double, 7, 1>::Constant(0.002);
    const int phase = i < 100 ? 0 : (i < 200 ? 1 : 2);
    truth.push_back(phase == 0 ? "stationary" : (phase == 1 ? "rotation" : "general"));
    if (phase == 0) w[0] = 1.0;
    if (phase == 1) w[1] = 0.6 + 0.3 * std::sin(i * 0.2), w[2] = 0.3;
    if (phase == 2) w[4] = 0.7, w[5] = 0.25 + 0.2 * std::cos(i * 0.3);
    if (i == 100 || i == 101 || i == 200 || i == 201) w[3] = w[6] = 0.8;  // spikes at switches
    w[6] = std::max(w[6], 0.0005);
    P.row(i) = (w / w.sum()).transpose();
  }
}
}  // namespace

TEST(VizPlot, ModelProbabilitiesWrittenSizedDeterministic)
{
  std::vector<double> t;
  std::vector<std::string> names, truth;
  MatX P;
  syntheticProbabilities(t, names, P, truth);
  TModelProbabilityPlotOptions o;
  o.truthLabels = truth;
  const std::string a = outDir() + "/model_probabilities.png", b = outDir() + "/model_probabilities_2.png";
  plotModelProbabilities(t, names, P, a, o);
  plotModelProbabilities(t, names, P, b, o);
  const cv::Mat img = cv::imread(a, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, o.width);
  EXPECT_EQ(img.rows, o.height);
  EXPECT_EQ(readBytes(a), readBytes(b));
  // The stacked area shows the stationary model's grey over the first third.
  EXPECT_GT(cv::norm(img, cv::Mat(img.size(), img.type(), cv::Scalar(255, 255, 255)), cv::NORM_L1), 0);

  TModelProbabilityPlotOptions l = o;
  l.style = EProbabilityStyle::Lines;
  l.logY = true;
  l.title = "Posterior model probabilities (log scale)";
  plotModelProbabilities(t, names, P, outDir() + "/model_probabilities_log.png", l);
  const cv::Mat i1 = modelProbabilitiesImage(t, names, P, l), i2 = modelProbabilitiesImage(t, names, P, l);
  EXPECT_EQ(cv::norm(i1, i2, cv::NORM_INF), 0.0);

  // Size errors name what is wrong.
  EXPECT_THROW(plotModelProbabilities(t, {"a"}, P, a), std::runtime_error);
  TModelProbabilityPlotOptions bad = o;
  bad.truthLabels.pop_back();
  EXPECT_THROW(modelProbabilitiesImage(t, names, P, bad), std::runtime_error);
  EXPECT_THROW(plotModelProbabilities(t, names, P, outDir() + "/no_dir/x.png", o), std::runtime_error);
}

TEST(VizPlot, SeriesLinearAndLog)
{
  TPlotSeries imm{"IMM", {}, {}, palette::kTrajectory, 2, false, false};
  TPlotSeries single{"single model", {}, {}, palette::kMapXyz, 2, false, true};
  for (int i = 0; i < 400; ++i)
  {
    const double t = i / 30.0;
    imm.x.push_back(t);
    single.x.push_back(t);
    imm.y.push_back(40 + 30 * std::exp(-t) + (i > 200 && i < 220 ? 80 : 0));
    single.y.push_back(900 + 300 * std::sin(0.05 * i));
  }
  single.y[50] = std::nan("");  // gaps are allowed
  TSeriesPlotOptions o;
  o.title = "Mean search-ellipse area (95 %)";
  o.yLabel = "area [px^2]";
  o.logY = true;
  const std::string a = outDir() + "/search_area.png";
  plotSeries({imm, single}, a, o);
  const cv::Mat img = cv::imread(a, cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.size(), cv::Size(o.width, o.height));
  EXPECT_EQ(cv::norm(seriesImage({imm, single}, o), seriesImage({imm, single}, o), cv::NORM_INF), 0.0);

  TPlotSeries ate{"ATE", imm.x, {}, palette::kGroundTruth, 2, false, false};
  for (size_t i = 0; i < ate.x.size(); ++i) ate.y.push_back(0.01 * std::sqrt(double(i)));
  TSeriesPlotOptions lo;
  lo.title = "Absolute trajectory error";
  lo.yLabel = "error [units]";
  plotSeries({ate}, outDir() + "/ate.png", lo);
  EXPECT_TRUE(std::filesystem::exists(outDir() + "/ate.png"));

  TPlotSeries broken = ate;
  broken.y.pop_back();
  EXPECT_THROW(seriesImage({broken}), std::runtime_error);
  EXPECT_THROW(seriesImage({}), std::runtime_error);
  EXPECT_THROW(CPlot(100, 100), std::runtime_error);
}
