/* Known-answer tests of the SLAM filter's map management (CMonoSlamIMM::manageMap, issue 30):
 *
 *  - MapManagement.DeletesAFeatureFoundTooRarelyAtTheTenthSearch: the MonoSLAM rule (searched at
 *    least delete_min_predictions = 10 times, matched in fewer than delete_min_match_ratio = 50 % of
 *    them). A feature matched 4 times in its first 10 searches goes at the 10th frame, not before;
 *    one matched 5 times in 10 (exactly 50 %) stays; the others (always matched) stay.
 *    "A feature is never deleted" fails here.
 *  - MapManagement.ConvertsToXyzExactlyBelowTheLinearityThreshold: a feature just initialised at
 *    the current camera has cos(alpha) = 1 and d = 1 / rho, so its linearity index (Civera, Davison &
 *    Montiel, ref. [3] of the IMM paper) is L = 4 sigma_rho / rho^2 * |cos alpha| / d = 4 sigma_rho / rho,
 *    and it is unchanged by a prediction with the velocity prior's zero mean (rho and its variance
 *    are invariant to a rigid motion). With linearity_threshold = 0.1, sigma_rho / rho = 0.0245 (L =
 *    0.098) converts at the next step and 0.0255 (L = 0.102) does not, at rho = 1 and at rho = 2. */
#include <gtest/gtest.h>
#include <immslam/tracking/CMonoSlamIMM.h>
#include <immslam/slam/measurement.h>

#include <algorithm>
#include <vector>

using namespace immslam;
using namespace immslam::slam;

namespace
{
camera::CCameraModel::Ptr testCamera()
{
  return camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
}
bool hasFeature(const CMonoSlamIMM& slam, std::int64_t id)
{
  const auto& fs = slam.features();
  return std::any_of(fs.begin(), fs.end(), [id](const TFeature& f) { return f.id == id; });
}
}  // namespace

TEST(MapManagement, DeletesAFeatureFoundTooRarelyAtTheTenthSearch)
{
  // A still camera over a still scene: each feature is measured at its first pixel (its prediction).
  // 14 features always measured keep the frame well tracked (never "lost").
  const auto cam = testCamera();
  CMonoSlamIMM::TOptions o;
  o.num_threads = 1;
  o.adaptive_pixel_noise = false;
  o.convert_to_xyz = false;  // deletion only
  o.relocalise = false;
  ASSERT_EQ(o.delete_min_predictions, 10);
  ASSERT_EQ(o.delete_min_match_ratio, 0.5);
  TIMMBankOptions b;
  b.models = "general:0.1";
  CMonoSlamIMM slam(o, b, COnePointRansac::TOptions(), cam);
  slam.processMeasurements(0.0, {});
  std::vector<Vec2> uv;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) uv.emplace_back(40 + 75 * i, 30 + 60 * j);
  const auto ids = slam.addFeaturesAt(cv::Mat(), uv, std::vector<std::pair<double, double>>(uv.size(), {1.0, 0.05}));
  ASSERT_EQ(slam.features().size(), 16u);
  const std::int64_t rare = ids[0], half = ids[1];
  // Frames 1..10: `rare` measured at frames 1-4 (4 of 10), `half` at frames 1-5 (5 of 10).
  for (int k = 1; k <= 12; ++k)
  {
    std::vector<std::pair<std::int64_t, Vec2>> z;
    for (std::size_t i = 0; i < ids.size(); ++i)
    {
      if (ids[i] == rare && k > 4) continue;
      if (ids[i] == half && k > 5) continue;
      z.emplace_back(ids[i], uv[i]);
    }
    const TFrameReport& rep = slam.processMeasurements(k / 30.0, z, true);
    ASSERT_GE(rep.nMatched, 14) << "frame " << k;
    if (k < 10)
    {
      EXPECT_TRUE(hasFeature(slam, rare)) << "deleted before its 10th search, frame " << k;
      EXPECT_EQ(rep.nDeleted, 0) << "frame " << k;
    }
    else if (k == 10)
    {
      EXPECT_FALSE(hasFeature(slam, rare)) << "4 matches in 10 searches: must be deleted at frame 10";
      EXPECT_EQ(rep.nDeleted, 1);
      EXPECT_EQ(slam.features().size(), 15u);
    }
    else  // frames 11, 12: `half` is at 5/11 and 5/12 < 50 %: deleted at frame 11
    {
      EXPECT_EQ(rep.nDeleted, k == 11 ? 1 : 0) << "frame " << k;
    }
    if (k <= 10)
    {
      EXPECT_TRUE(hasFeature(slam, half)) << "5 of 10 is not below 50 %, frame " << k;
    }
  }
  EXPECT_FALSE(hasFeature(slam, half));
  EXPECT_EQ(slam.features().size(), 14u);
  // The rest of the state follows the deletions: 13 + 6 per feature in every mode.
  EXPECT_EQ(slam.fusedMean().size(), 13 + 6 * 14);
}

TEST(MapManagement, ConvertsToXyzExactlyBelowTheLinearityThreshold)
{
  const auto cam = testCamera();
  CMonoSlamIMM::TOptions o;
  o.num_threads = 1;
  o.adaptive_pixel_noise = false;
  o.convert_to_xyz = true;
  ASSERT_EQ(o.linearity_threshold, 0.1);
  TIMMBankOptions b;
  b.models = "general:0.1";
  CMonoSlamIMM slam(o, b, COnePointRansac::TOptions(), cam);
  slam.processMeasurements(0.0, {});
  // (rho, sigma_rho): L = 4 sigma_rho / rho = 0.098, 0.102, 0.098, 0.102.
  const std::vector<std::pair<double, double>> prior = {{1.0, 0.0245}, {1.0, 0.0255}, {2.0, 0.049}, {2.0, 0.051}};
  const std::vector<bool> converts = {true, false, true, false};
  const std::vector<Vec2> uv = {Vec2(100, 80), Vec2(220, 80), Vec2(100, 160), Vec2(220, 160)};
  const auto ids = slam.addFeaturesAt(cv::Mat(), uv, prior);
  for (const auto& f : slam.features()) EXPECT_EQ(f.kind, EFeatureKind::InverseDepth);
  const TFrameReport& rep = slam.processMeasurements(1 / 30.0, {});
  EXPECT_EQ(rep.nConverted, 2);
  ASSERT_EQ(slam.features().size(), 4u);
  for (std::size_t k = 0; k < ids.size(); ++k)
  {
    const TFeature& f = slam.features()[k];
    ASSERT_EQ(f.id, ids[k]);
    EXPECT_EQ(f.kind == EFeatureKind::XYZ, converts[k])
        << "rho " << prior[k].first << ", sigma_rho " << prior[k].second << ": L = " << 4 * prior[k].second / prior[k].first;
    // The converted point is where the inverse-depth feature was: on the ray of its pixel at 1 / rho.
    if (f.kind == EFeatureKind::XYZ)
    {
      const Vec3 p = slam.fusedMean().segment<3>(f.offset);
      EXPECT_NEAR(p.norm(), 1.0 / prior[k].first, 1e-9);
      Vec2 back;
      ASSERT_TRUE(predictMeasurement(*cam, slam.fusedMean(), f, back));
      EXPECT_LT((back - uv[k]).norm(), 1e-6);
    }
  }
  EXPECT_EQ(slam.fusedMean().size(), 13 + 3 + 6 + 3 + 6);
}

TEST(IMMSlamBank, ProbabilityFloorHoldsAfterADecisiveFrame)
{
  // TIMMBankOptions::probability_floor reaches the bank: a stationary and a general mode, the camera moves 0.05
  // sideways (10 px at the features' unit depth, sigma 1 px): the stationary mode's likelihood is
  // ~e^-300 of the general one's, so its posterior is the floor, 1e-4, exactly (not ~0), and the
  // general mode holds the rest.
  const auto cam = testCamera();
  CMonoSlamIMM::TOptions o;
  o.num_threads = 1;
  o.adaptive_pixel_noise = false;
  o.init_linear_velocity_std_px = 20;
  o.init_angular_velocity_std_px = 0.5;
  o.convert_to_xyz = false;
  o.relocalise = false;
  TIMMBankOptions b;
  b.models = "stationary general:0.5";
  b.probability_floor = 1e-4;
  b.dormant_below = 0;  // the exact IMM
  CMonoSlamIMM slam(o, b, COnePointRansac::TOptions(), cam);
  slam.processMeasurements(0.0, {});
  std::vector<Vec2> uv;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 3; ++j) uv.emplace_back(50 + 70 * i, 50 + 70 * j);
  const auto ids = slam.addFeaturesAt(cv::Mat(), uv, std::vector<std::pair<double, double>>(uv.size(), {1.0, 0.01}));
  std::vector<std::pair<std::int64_t, Vec2>> z;
  for (std::size_t k = 0; k < uv.size(); ++k)
  {
    Vec2 m;
    ASSERT_TRUE(cam->project(cam->unproject(uv[k]).unitVector() - Vec3(0.05, 0, 0), m));
    z.emplace_back(ids[k], m);
  }
  const TFrameReport& rep = slam.processMeasurements(1 / 30.0, z, true);
  EXPECT_EQ(rep.nMatched, 12);
  const VecX mu = slam.modelProbabilities();
  EXPECT_NEAR(mu[0], 1e-4, 1e-12);
  EXPECT_NEAR(mu[1], 1 - 1e-4, 1e-12);
}
