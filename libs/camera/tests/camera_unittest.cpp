/* Tests: camera models (Jacobians vs numerical, round trips, domains, scaling, no allocations). */
#include "test_cameras.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <opencv2/calib3d.hpp>
#include <immslam/math/numerical_jacobian.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <memory>
#include <new>
#include <random>

using namespace immslam;
using namespace immslam::camera;
using immslam::camera::test::TTestCamera;

// Counting allocator for the "project() does not allocate" test. Replacing the global operator new
// is the language's only hook for this, hence the file-scope counter (tests only).
// (Eigen's own aligned allocations bypass operator new; project() uses fixed-size types only.)
static std::atomic<long> g_allocations{0};
__attribute__((noinline)) static void* countedAlloc(std::size_t n)
{
  ++g_allocations;
  return std::malloc(n ? n : 1);
}
__attribute__((noinline)) static void countedFree(void* p) { std::free(p); }
void* operator new(std::size_t n)
{
  if (void* p = countedAlloc(n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { countedFree(p); }
void operator delete(void* p, std::size_t) noexcept { countedFree(p); }

namespace
{
/** Random points in front of the camera whose projection falls in the image. */
std::vector<Vec3> pointsInImage(const CCameraModel& cam, int n, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> tanDist(-2.6, 2.6), depth(0.2, 20.0);
  std::vector<Vec3> pts;
  for (int attempt = 0; attempt < 1000000 && static_cast<int>(pts.size()) < n; ++attempt)
  {
    const double z = depth(rng);
    const Vec3 p(tanDist(rng) * z, tanDist(rng) * z, z);
    Vec2 uv;
    if (cam.project(p, uv) && cam.isInImage(uv)) pts.push_back(p);
  }
  return pts;
}

/** Pixel coordinates every `step` px from -0.5 to size - 0.5, both pixel-centre borders included. */
std::vector<double> gridCoords(int size, double step)
{
  std::vector<double> c{-0.5};
  for (double x = 0; x < size - 1; x += step) c.push_back(x);
  c.push_back(size - 1);
  c.push_back(size - 0.5);
  return c;
}

double relErr(const MatX& a, const MatX& b) { return (a - b).norm() / b.norm(); }

class CameraModelTest : public ::testing::TestWithParam<TTestCamera>
{
};
}  // namespace

TEST_P(CameraModelTest, ProjectJacobianMatchesNumerical)
{
  const CCameraModel& cam = *GetParam().cam;
  const auto pts = pointsInImage(cam, 300, 11);
  ASSERT_GE(pts.size(), 200u);
  double worst = 0;
  for (const Vec3& p : pts)
  {
    Vec2 uv;
    Mat23 J;
    ASSERT_TRUE(cam.project(p, uv, &J));
    Vec2 uv2;
    ASSERT_TRUE(cam.project(p, uv2));
    EXPECT_EQ(uv, uv2);  // same value with or without the Jacobian
    const MatX Jn = math::numericalJacobian(
        [&](const VecX& x) -> VecX {
          Vec2 u;
          EXPECT_TRUE(cam.project(x, u));
          return u;
        },
        VecX(p), 1e-6 * p.norm());
    worst = std::max(worst, relErr(J, Jn));
  }
  EXPECT_LT(worst, 1e-6);
}

TEST_P(CameraModelTest, ProjectIsScaleInvariant)
{
  const CCameraModel& cam = *GetParam().cam;
  for (const Vec3& p : pointsInImage(cam, 50, 12))
  {
    Vec2 a, b;
    ASSERT_TRUE(cam.project(p, a));
    ASSERT_TRUE(cam.project(0.01 * p, b));
    EXPECT_LT((a - b).norm(), 1e-9);
  }
}

TEST_P(CameraModelTest, UnprojectJacobianMatchesNumerical)
{
  const CCameraModel& cam = *GetParam().cam;
  double worst = 0;
  int n = 0;
  for (const double u : gridCoords(cam.width(), 16))
    for (const double v : gridCoords(cam.height(), 16))
    {
      Mat32 J;
      const Vec2 uv(u, v);
      const Vec3 b = cam.unproject(uv, &J).unitVector();
      EXPECT_LT((cam.unproject(uv).unitVector() - b).norm(), 1e-15);
      const MatX Jn = math::numericalJacobian(
          [&](const VecX& x) -> VecX { return cam.unproject(x).unitVector(); }, VecX(uv), 1e-3);
      worst = std::max(worst, relErr(J, Jn));
      ++n;
    }
  EXPECT_GT(n, 300);
  EXPECT_LT(worst, 1e-6);
}

TEST_P(CameraModelTest, ProjectUnprojectRoundTripOverWholeImage)
{
  const CCameraModel& cam = *GetParam().cam;
  double worst = 0;
  int n = 0, failed = 0;
  for (const double u : gridCoords(cam.width(), 4))
    for (const double v : gridCoords(cam.height(), 4))
    {
      const Vec2 uv(u, v);
      const Vec3 b = cam.unproject(uv).unitVector();
      EXPECT_GT(b.z(), 0);
      Vec2 back;
      if (!cam.project(b, back))
        ++failed;
      else
        worst = std::max(worst, (back - uv).norm());
      ++n;
    }
  EXPECT_EQ(failed, 0);
  EXPECT_LT(worst, 1e-6) << n << " pixels";
}

TEST_P(CameraModelTest, UnprojectProjectGivesTheSameRay)
{
  const CCameraModel& cam = *GetParam().cam;
  for (const Vec3& p : pointsInImage(cam, 300, 13))
  {
    Vec2 uv;
    ASSERT_TRUE(cam.project(p, uv));
    const Vec3 b = cam.unproject(uv).unitVector();
    EXPECT_LT(b.cross(p.normalized()).norm(), 1e-9);
    EXPECT_GT(b.dot(p), 0);
  }
}

TEST_P(CameraModelTest, PointsBehindOrBesideTheCameraDoNotProject)
{
  const CCameraModel& cam = *GetParam().cam;
  Vec2 uv;
  Mat23 J;
  EXPECT_FALSE(cam.project(Vec3(0.1, 0.2, -1.0), uv, &J));
  EXPECT_FALSE(cam.project(Vec3(0, 0, -1e-3), uv));
  EXPECT_FALSE(cam.project(Vec3(1, 2, 0), uv));
  EXPECT_FALSE(cam.project(Vec3(1, 0, 0.5e-9), uv));  // z <= 1e-9 |p|
  EXPECT_FALSE(cam.project(Vec3(0, 0, 0), uv));
  EXPECT_FALSE(cam.project(Vec3(std::nan(""), 0, 1), uv));
  EXPECT_TRUE(cam.project(Vec3(0.01, -0.02, 1.0), uv, &J));
}

TEST_P(CameraModelTest, ScaledMapsTheSameRayToTheScaledPixel)
{
  const CCameraModel& cam = *GetParam().cam;
  for (const double s : {0.5, 2.0, 1.0 / 3.0, 0.25})
  {
    const CCameraModel::Ptr sc = cam.scaled(s);
    EXPECT_EQ(sc->modelName(), cam.modelName());
    EXPECT_EQ(sc->width(), std::lround(s * cam.width()));
    EXPECT_EQ(sc->height(), std::lround(s * cam.height()));
    EXPECT_NEAR(sc->fx(), s * cam.fx(), 1e-12);
    for (const Vec3& p : pointsInImage(cam, 50, 14))
    {
      Vec2 uv, uvs;
      ASSERT_TRUE(cam.project(p, uv));
      ASSERT_TRUE(sc->project(p, uvs));
      const Vec2 expected = s * (uv + Vec2(0.5, 0.5)) - Vec2(0.5, 0.5);
      EXPECT_LT((uvs - expected).norm(), 1e-9) << "s = " << s;
      EXPECT_LT((sc->unproject(uvs).unitVector() - p.normalized()).norm(), 1e-9);
    }
  }
  EXPECT_THROW(cam.scaled(0.0), std::runtime_error);
  EXPECT_THROW(cam.scaled(-1.0), std::runtime_error);
}

TEST_P(CameraModelTest, CalibLineRoundTripIsExact)
{
  const CCameraModel& cam = *GetParam().cam;
  for (const CCameraModel::Ptr& c : {GetParam().cam, cam.scaled(1.0 / 3.0)})
  {
    const CCameraModel::Ptr back = parseCalibLine(c->toCalibLine(), "test");
    EXPECT_EQ(back->modelName(), c->modelName());
    EXPECT_EQ(back->width(), c->width());
    EXPECT_EQ(back->height(), c->height());
    EXPECT_EQ(back->parameters(), c->parameters()) << c->toCalibLine();
  }
}

TEST_P(CameraModelTest, ProjectDoesNotAllocate)
{
  const CCameraModel& cam = *GetParam().cam;
  const auto pts = pointsInImage(cam, 100, 15);
  Vec2 uv;
  Mat23 J;
  double sum = 0;
  const long before = g_allocations.load();
  for (const Vec3& p : pts)
  {
    if (cam.project(p, uv)) sum += uv.x();
    if (cam.project(p, uv, &J)) sum += J(0, 0);
    sum += cam.isInImage(uv, 5.0);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_TRUE(std::isfinite(sum));
  // The counter does see allocations.
  const auto probe = std::make_unique<std::vector<double>>(100);
  EXPECT_GE(g_allocations.load() - before, 2);
}

INSTANTIATE_TEST_SUITE_P(AllModels, CameraModelTest, ::testing::ValuesIn(test::testCameras()),
    [](const ::testing::TestParamInfo<TTestCamera>& p) { return p.param.name; });

TEST(CameraModel, IsInImageUsesPixelAreaBorders)
{
  const CPinholeCamera cam(320, 240, 170, 170, 160, 120);
  EXPECT_TRUE(cam.isInImage(Vec2(-0.5, -0.5)));
  EXPECT_TRUE(cam.isInImage(Vec2(319.5, 239.5)));
  EXPECT_FALSE(cam.isInImage(Vec2(-0.51, 10)));
  EXPECT_FALSE(cam.isInImage(Vec2(10, 239.51)));
  EXPECT_TRUE(cam.isInImage(Vec2(4.5, 4.5), 5));  // nearest pixel 5: an 11x11 patch from 0 fits
  EXPECT_FALSE(cam.isInImage(Vec2(4.4, 100), 5));
  EXPECT_TRUE(cam.isInImage(Vec2(314.5, 100), 5));
  EXPECT_FALSE(cam.isInImage(Vec2(314.6, 100), 5));
}

TEST(CameraModel, ConstructorsRejectBadParameters)
{
  EXPECT_THROW(CPinholeCamera(0, 240, 170, 170, 160, 120), std::runtime_error);
  EXPECT_THROW(CPinholeCamera(320, -1, 170, 170, 160, 120), std::runtime_error);
  EXPECT_THROW(CPinholeCamera(320, 240, 0, 170, 160, 120), std::runtime_error);
  EXPECT_THROW(CPinholeCamera(320, 240, 170, -5, 160, 120), std::runtime_error);
  EXPECT_THROW(CPinholeCamera(320, 240, 170, 170, INFINITY, 120), std::runtime_error);
  EXPECT_THROW(COpenCVCamera(320, 240, 170, 170, 160, 120, NAN, 0, 0, 0, 0), std::runtime_error);
  EXPECT_THROW(CDavisonCamera(320, 240, 170, 170, 160, 120, INFINITY), std::runtime_error);
}

TEST(OpenCVCamera, FoldBackRadiusIsRespected)
{
  const auto cam = test::strongOpenCVCamera();
  const double rMax = cam->maxUndistortedRadius();
  ASSERT_TRUE(std::isfinite(rMax));
  const auto slope = [&](double r) {
    const double s = r * r;
    return 1 + 3 * cam->k1() * s + 5 * cam->k2() * s * s + 7 * cam->k3() * s * s * s;
  };
  EXPECT_NEAR(slope(rMax), 0.0, 1e-12);
  EXPECT_GT(slope(0.999 * rMax), 0.0);
  EXPECT_LT(slope(1.001 * rMax), 0.0);
  Vec2 uv;
  for (const double ang : {0.0, 0.7, 2.0, 4.0})
  {
    const Vec2 dir(std::cos(ang), std::sin(ang));
    EXPECT_TRUE(cam->project(Vec3(0.99 * rMax * dir.x(), 0.99 * rMax * dir.y(), 1), uv));
    EXPECT_FALSE(cam->project(Vec3(1.01 * rMax * dir.x(), 1.01 * rMax * dir.y(), 1), uv));
    // Pixels beyond the largest distorted radius unproject onto the valid branch.
    const Vec3 b = cam->unproject(Vec2(cam->cx() + 5000 * dir.x(), cam->cy() + 5000 * dir.y())).unitVector();
    EXPECT_GT(b.z(), 0);
    EXPECT_LE(std::hypot(b.x(), b.y()) / b.z(), rMax);
    EXPECT_GT(std::hypot(b.x(), b.y()) / b.z(), 0.99 * rMax);
  }

  // EuRoC (k1 = -0.283, k2 = 0.074): 1 + 3 k1 s + 5 k2 s^2 has no real root, monotone everywhere;
  // with k1 alone it would fold at r = 1/sqrt(3 |k1|).
  EXPECT_TRUE(std::isinf(test::eurocCamera()->maxUndistortedRadius()));
  const COpenCVCamera k1only(752, 480, 458.654, 457.296, 367.215, 248.375, -0.28340811, 0, 0, 0, 0);
  EXPECT_NEAR(k1only.maxUndistortedRadius(), 1.0 / std::sqrt(3 * 0.28340811), 1e-12);
  EXPECT_FALSE(k1only.project(Vec3(1.1, 0, 1), uv));
  EXPECT_TRUE(k1only.project(Vec3(1.08, 0, 1), uv));
  // Pincushion k1 > 0 with k2 < 0 folds too.
  const COpenCVCamera pin(640, 480, 500, 500, 320, 240, 0.2, -0.1, 0, 0, 0);
  EXPECT_TRUE(std::isfinite(pin.maxUndistortedRadius()));
}

TEST(OpenCVCamera, UndistortInvertsDistortToMachinePrecision)
{
  const auto cam = test::strongOpenCVCamera();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> d(-1.5, 1.5);
  for (int i = 0; i < 1000; ++i)
  {
    const Vec2 n(d(rng), d(rng));
    if (n.norm() >= cam->maxUndistortedRadius()) continue;
    EXPECT_LT((cam->undistort(cam->distort(n)) - n).norm() * cam->fx(), 1e-10);
  }
}

TEST(DavisonCamera, DomainIsHandledGracefully)
{
  const auto cam = test::monoslamCamera();
  Vec2 uv;
  // kd1 > 0: every ray in front projects, inside the limit radius 1/sqrt(2 kd1).
  const double rLimit = 1.0 / std::sqrt(2 * cam->kd1());
  EXPECT_TRUE(cam->project(Vec3(std::tan(1.55), 0, 1), uv));
  EXPECT_LT(uv.x() - cam->cx(), rLimit);
  // Pixels at or beyond the limit radius still unproject to a finite ray in front.
  for (const double r : {rLimit - 1e-9, rLimit, rLimit + 1, 1000.0})
  {
    Mat32 J;
    const Vec3 b = cam->unproject(Vec2(cam->cx(), cam->cy() + r), &J).unitVector();
    EXPECT_GT(b.z(), 0);
    EXPECT_TRUE(b.allFinite() && J.allFinite());
  }
  // kd1 < 0: rays beyond r_u = 1/sqrt(-2 kd1) do not project.
  const CDavisonCamera pin(320, 240, 200, 200, 160, 120, -1e-5);
  const double ru = 1.0 / std::sqrt(2e-5);
  EXPECT_TRUE(pin.project(Vec3(0.99 * ru / 200, 0, 1), uv));
  EXPECT_FALSE(pin.project(Vec3(1.01 * ru / 200, 0, 1), uv));
}

TEST(DavisonCamera, MatchesTheReadmeFormulaAndScalesKd1)
{
  const auto cam = test::monoslamCamera();
  const Vec3 p(0.3, -0.2, 1.0);
  Vec2 uv;
  ASSERT_TRUE(cam->project(p, uv));
  const double du = 195 * 0.3, dv = 195 * -0.2, ru = std::hypot(du, dv);
  const double rd = ru / std::sqrt(1 + 2 * 9e-6 * ru * ru);
  EXPECT_NEAR(uv.x(), 162 + du * rd / ru, 1e-12);
  EXPECT_NEAR(uv.y(), 125 + dv * rd / ru, 1e-12);
  const auto half = std::dynamic_pointer_cast<const CDavisonCamera>(cam->scaled(0.5));
  ASSERT_TRUE(half);
  EXPECT_DOUBLE_EQ(half->kd1(), 4 * 9e-6);
  EXPECT_DOUBLE_EQ(half->cx(), 0.5 * 162.5 - 0.5);
  const auto sc = std::dynamic_pointer_cast<const COpenCVCamera>(test::eurocCamera()->scaled(0.5));
  ASSERT_TRUE(sc);
  EXPECT_EQ(sc->parameters()[4], -0.28340811);
  EXPECT_EQ(sc->k2(), 0.07395907);
}

TEST(DavisonCamera, ScalingThatOverflowsKd1IsRefusedWithAClearError)
{
  // Found by fuzz_calib: kd1 = 1e308 is finite, kd1 / 0.5^2 is not.
  const CDavisonCamera cam(80, 240, 195, 195, 162, 125, 1e308);
  try
  {
    (void)cam.scaled(0.5);
    FAIL() << "scaled(0.5) accepted a non-finite kd1";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("davison camera: scaling by 0.5"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW((void)cam.scaled(2.0));  // kd1 / 4 stays finite
}

TEST(FisheyeCamera, MatchesOpenCVsFisheyeModel)
{
  // OpenCV's cv::fisheye is the reference implementation of the model (its documentation's formula);
  // project the same points through both.
  const std::vector<std::shared_ptr<const CFisheyeCamera>> cams{
      test::tumviCamera(),
      std::make_shared<CFisheyeCamera>(640, 480, 300, 301, 319.5, 239.5, -0.012, 0.0051, -0.0013, 0.00015)};
  for (const auto& cam : cams)
  {
    std::mt19937 rng(21);
    std::uniform_real_distribution<double> angle(0, 1.5), phi(-M_PI, M_PI), dist(0.1, 30);
    std::vector<cv::Point3d> pts;
    for (int i = 0; i < 500; ++i)
    {
      const double th = angle(rng), ph = phi(rng), d = dist(rng);
      pts.emplace_back(d * std::sin(th) * std::cos(ph), d * std::sin(th) * std::sin(ph), d * std::cos(th));
    }
    const cv::Matx33d K(cam->fx(), 0, cam->cx(), 0, cam->fy(), cam->cy(), 0, 0, 1);
    const cv::Vec4d D(cam->k1(), cam->k2(), cam->k3(), cam->k4());
    std::vector<cv::Point2d> ref;
    cv::fisheye::projectPoints(pts, ref, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D);
    double worst = 0;
    for (std::size_t i = 0; i < pts.size(); ++i)
    {
      Vec2 uv;
      ASSERT_TRUE(cam->project(Vec3(pts[i].x, pts[i].y, pts[i].z), uv));
      worst = std::max(worst, (uv - Vec2(ref[i].x, ref[i].y)).norm());
    }
    EXPECT_LT(worst, 1e-9);
  }
}

TEST(FisheyeCamera, PixelsBeyondTheHemisphereUnprojectToTheLimitRay)
{
  // TUM-VI's 512x512 corners lie outside its image circle, beyond 90 degrees from the axis: they
  // unproject to the ray at the limit, in front of the camera, with finite Jacobians.
  const auto cam = test::tumviCamera();
  EXPECT_NEAR(cam->maxAngle(), 0.5 * M_PI, 1e-8);
  for (const Vec2& corner : {Vec2(-0.5, -0.5), Vec2(511.5, 511.5), Vec2(-0.5, 511.5)})
  {
    Mat32 J;
    const Vec3 b = cam->unproject(corner, &J).unitVector();
    EXPECT_GT(b.z(), 0);
    EXPECT_LT(b.z(), 1e-6);
    EXPECT_TRUE(J.allFinite());
    Vec2 uv;
    EXPECT_TRUE(cam->project(b, uv));  // the limit ray still projects (on the image circle)
    EXPECT_LT((uv - Vec2(cam->cx(), cam->cy())).norm(), (corner - Vec2(cam->cx(), cam->cy())).norm());
    EXPECT_FALSE(cam->imagesPixel(corner));
  }
  EXPECT_TRUE(cam->imagesPixel(Vec2(cam->cx(), cam->cy())));
  EXPECT_TRUE(cam->imagesPixel(Vec2(10, 256)));
  // 80 degrees off the axis towards a corner is inside the image (the diagonal sees more than 180).
  Vec2 uv;
  const double s80 = std::sin(80 * M_PI / 180);
  ASSERT_TRUE(cam->project(Vec3(s80 * M_SQRT1_2, s80 * M_SQRT1_2, std::cos(80 * M_PI / 180)), uv));
  EXPECT_TRUE(cam->isInImage(uv));
}

TEST(FisheyeCamera, FoldOfTheAngleMapIsRespected)
{
  // theta_d = theta (1 - 0.5 theta^2): slope 1 - 1.5 theta^2 vanishes at theta = sqrt(2/3).
  const CFisheyeCamera cam(640, 480, 300, 300, 319.5, 239.5, -0.5, 0, 0, 0);
  EXPECT_NEAR(cam.maxAngle(), std::sqrt(2.0 / 3.0), 1e-12);
  Vec2 uv;
  const double inside = 0.99 * cam.maxAngle(), beyond = 1.01 * cam.maxAngle();
  EXPECT_TRUE(cam.project(Vec3(std::sin(inside), 0, std::cos(inside)), uv));
  EXPECT_FALSE(cam.project(Vec3(std::sin(beyond), 0, std::cos(beyond)), uv));
  // A pixel beyond the largest distorted angle: the ray at the fold.
  const double rMax = 300 * cam.distortAngle(cam.maxAngle());
  const Vec3 b = cam.unproject(Vec2(319.5 + rMax + 20, 239.5)).unitVector();
  EXPECT_NEAR(std::atan2(b.head<2>().norm(), b.z()), cam.maxAngle(), 1e-9);
  // Inside, the inverse is exact.
  for (const double th : {0.0, 1e-12, 1e-6, 0.1, 0.5, 0.8})
  {
    if (th >= cam.maxAngle()) continue;
    EXPECT_NEAR(cam.undistortAngle(cam.distortAngle(th)), th, 1e-14);
  }
  EXPECT_THROW(CFisheyeCamera(640, 480, 300, 300, 319.5, 239.5, std::nan(""), 0, 0, 0), std::runtime_error);
}
