/* imm-monoslam — the IMM SLAM filter used on its own, without images: CImmSlamFilter's header is the
 * first include, so this file does not compile if it brings OpenCV in. */
#include <immslam/slam/CImmSlamFilter.h>

#ifdef CV_VERSION_MAJOR
#error "CImmSlamFilter.h pulls in OpenCV"
#endif

#include <immslam/camera/CCameraModel.h>
#include <immslam/math/bearing.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/math/quaternion.h>
#include <immslam/tracking/CSlamTracker.h>

#include <Eigen/LU>
#include <gtest/gtest.h>

#include <random>

using namespace immslam;
using namespace immslam::slam;

namespace
{
/** A static cloud seen by a still camera: the features' pixels and 1-px noise. */
struct TStillScene
{
  std::vector<Vec2> uv0;
  std::mt19937 rng{7};
  std::normal_distribution<double> g;
  TStillScene()
  {
    for (int j = 0; j < 24; ++j) uv0.emplace_back(30 + 260.0 * (j % 6) / 5, 30 + 180.0 * (j / 6) / 3);
  }
  std::vector<std::pair<std::int64_t, Vec2>> measure(const std::vector<std::int64_t>& ids)
  {
    std::vector<std::pair<std::int64_t, Vec2>> z;
    for (std::size_t j = 0; j < ids.size(); ++j) z.emplace_back(ids[j], uv0[j] + Vec2(g(rng), g(rng)));
    return z;
  }
};

std::vector<TCandidate> candidates(const CImmSlamFilter& f, const std::vector<std::pair<std::int64_t, Vec2>>& z)
{
  std::vector<TCandidate> c;
  for (const auto& [id, uv] : z)
    for (int k = 0; k < static_cast<int>(f.features().size()); ++k)
      if (f.features()[k].id == id) c.push_back(TCandidate{k, uv, Vec2::Zero(), Mat2F(), Mat2::Identity()});
  return c;
}
}  // namespace

TEST(ImmSlamFilter, PredictMeasureUpdateWithoutImagesKeepsAValidBank)
{
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  CImmSlamFilter::TOptions o;
  o.num_threads = 1;
  CImmSlamFilter filter(o, TIMMBankOptions(), cam);
  TStillScene scene;
  ASSERT_EQ(filter.beginFrame(), 0);
  filter.start(0.0);
  std::vector<CImmSlamFilter::TNewFeature> fresh;
  for (const Vec2& uv : scene.uv0) fresh.push_back({uv, 1.0, 1.0, filter.allocateId()});
  const auto ids = filter.addFeatures(fresh);
  ASSERT_EQ(filter.features().size(), scene.uv0.size());
  for (int k = 1; k <= 20; ++k)
  {
    filter.beginFrame();
    EXPECT_EQ(filter.predict(k / 30.0), 1.0);
    // The fused predicted measurements and their ellipses (eqs. 13-14): positive definite.
    for (const auto& f : filter.features())
    {
      Vec2 h;
      Mat2F J;
      ASSERT_TRUE(filter.predictedMeasurement(f, h, &J));
      const Mat2 S = filter.predictedInnovationCovariance(f, J);
      EXPECT_GT(S.determinant(), 0.0);
      EXPECT_NEAR(S(0, 1), S(1, 0), 1e-12);
    }
    const auto cands = candidates(filter, scene.measure(ids));
    std::vector<int> all(cands.size());
    for (std::size_t c = 0; c < cands.size(); ++c) all[c] = static_cast<int>(c);
    EXPECT_EQ(filter.update(cands, all), static_cast<int>(cands.size()));
    filter.finishUpdate();
    const VecX mu = filter.modelProbabilities();
    EXPECT_NEAR(mu.sum(), 1.0, 1e-9);
    EXPECT_TRUE((mu.array() >= 0).all());
  }
  // A still camera stays where it was.
  EXPECT_LT(filter.cameraPosition().norm(), 0.05);
  const MatX P = filter.fusedCovariance();
  EXPECT_LT((P - P.transpose()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_TRUE((P.diagonal().array() >= 0).all());
  // Map operations: remove one feature, convert none, drop the first.
  filter.removeFeatures({ids[3]});
  EXPECT_EQ(filter.features().size(), scene.uv0.size() - 1);
  std::vector<char> drop(filter.features().size(), 0), convert(filter.features().size(), 0);
  drop[0] = 1;
  filter.reparametrizeMap(drop, convert);
  EXPECT_EQ(filter.features().size(), scene.uv0.size() - 2);
  EXPECT_EQ(filter.fusedMean().size(), motion::kCamDim + 6 * static_cast<int>(filter.features().size()));
}

TEST(ImmSlamFilter, TrackerKnownAssociationStepIsTheFilterStepBitForBit)
{
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  CSlamTracker::TOptions o;
  o.num_threads = 1;
  o.convert_to_xyz = false;  // (the tracker's map policy; the filter alone converts nothing)
  CSlamTracker tracker(o, TIMMBankOptions(), COnePointRansac::TOptions(), cam);
  CImmSlamFilter filter(o.filterOptions(), TIMMBankOptions(), cam);
  TStillScene a, b;
  tracker.processMeasurements(0.0, {});
  const auto idsT = tracker.addFeaturesAt(cv::Mat(), a.uv0);
  filter.beginFrame();
  filter.start(0.0);
  std::vector<CImmSlamFilter::TNewFeature> fresh;
  for (const Vec2& uv : b.uv0) fresh.push_back({uv, o.init_rho, o.init_rho_std, filter.allocateId()});
  const auto idsF = filter.addFeatures(fresh);
  ASSERT_EQ(idsT, idsF);
  for (int k = 1; k <= 10; ++k)
  {
    tracker.processMeasurements(k / 30.0, a.measure(idsT), false);
    filter.beginFrame();
    filter.predict(k / 30.0);
    const auto cands = candidates(filter, b.measure(idsF));
    std::vector<int> all(cands.size());
    for (std::size_t c = 0; c < cands.size(); ++c) all[c] = static_cast<int>(c);
    filter.update(cands, all);
    filter.finishUpdate();
    ASSERT_TRUE(tracker.fusedMean() == filter.fusedMean()) << "frame " << k;
    ASSERT_TRUE(tracker.modelProbabilities() == filter.modelProbabilities()) << "frame " << k;
  }
}

TEST(ImmSlamFilter, FeatureWorldEstimateMatchesNumericalJacobians)
{
  // A rotated and displaced camera (relocalisation's pose correction), then the features' world view:
  // the anchor and angles give the fused position, and Cov(theta, phi, rho)_W is J P J^T with J the
  // numerical Jacobian of the angles' rotation into W.
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  CImmSlamFilter::TOptions o;
  o.num_threads = 1;
  CImmSlamFilter filter(o, TIMMBankOptions(), cam);
  TStillScene scene;
  filter.beginFrame();
  filter.start(0.0);
  std::vector<CImmSlamFilter::TNewFeature> fresh;
  for (const Vec2& uv : scene.uv0) fresh.push_back({uv, 0.5, 0.2, filter.allocateId()});
  const auto ids = filter.addFeatures(fresh);
  filter.beginFrame();
  filter.predict(1 / 30.0);
  const Vec4 q_CW = math::quatFromRotationVector(Vec3(0.3, -0.5, 0.2));
  filter.correctPose(Vec3(0.4, -0.1, 0.7), q_CW, 0.01, 0.01, Vec6::Zero(), 1e-4 * Mat6::Identity());
  filter.finishUpdate();
  ASSERT_EQ(ids.size(), scene.uv0.size());
  const Vec3 r_WC = filter.cameraPosition();
  const Vec4 q_WC = filter.cameraOrientation();
  ASSERT_GT(r_WC.norm(), 0.1);
  int checked = 0;
  for (const auto& f : filter.features())
  {
    const TFeatureWorldEstimate e = filter.featureWorldEstimate(f);
    ASSERT_TRUE(e.inverseDepth);
    const Vec3 p = e.anchor_W + math::Bearing::DirectionFromAngles(e.theta, e.phi) / e.rho;
    EXPECT_LT((p - e.p_W).norm(), 1e-9 * (1 + e.p_W.norm()));
    const VecX y = filter.fusedMean().segment(f.offset, 6);
    const auto worldAngles = [&](const VecX& tpr) -> VecX
    {
      const Vec3 mW = math::quatRotate(q_WC, math::Bearing::DirectionFromAngles(tpr[0], tpr[1]));
      const Vec2 a = math::Bearing::AzimuthElevation(mW);
      return Vec3(a[0], a[1], tpr[2]);
    };
    const MatX J = math::numericalJacobian(worldAngles, VecX(y.tail<3>()));
    const Mat3 Pa = filter.fusedCovarianceBlock(f.offset + 3, 3);
    const Mat3 expected = J * Pa * J.transpose();
    EXPECT_LT((e.cov_tpr - expected).cwiseAbs().maxCoeff(), 1e-6 * expected.cwiseAbs().maxCoeff());
    ++checked;
  }
  EXPECT_EQ(checked, static_cast<int>(scene.uv0.size()));
}
