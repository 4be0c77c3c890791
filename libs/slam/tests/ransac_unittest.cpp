/* Known-answer tests of the SLAM filter's mismatch rejection (issue 30): 1-point RANSAC
 * (COnePointRansac, Civera et al. JFR 2010) and the high-innovation rescue of CMonoSlamIMM.
 *
 * What they prove:
 *  - OnePointRansac.RecoversTheExactInlierSet: on a synthetic problem whose inlier set is known by
 *    construction (30 % and 50 % outliers), lowInnovationInliers returns exactly that set, for
 *    every seed. "Accept every match" fails here.
 *  - OnePointRansac.AdaptiveHypothesisCountFollowsTheFormula: the number of hypotheses tried is the
 *    documented adaptive count n_hyp = log(1 - p) / log(1 - eps) for the true inlier ratio eps, or
 *    the draw that first hit an inlier if that came later (computed from a copy of the random
 *    stream, by hand); with no outlier, exactly 1.
 *  - OnePointRansac.HighInnovationRescue: a match off its single-point prediction but on its
 *    epipolar line (depth unknown) is rescued; one 8 px off that line is rejected; the others are
 *    low-innovation inliers. */
#include <gtest/gtest.h>
#include <immslam/tracking/CMonoSlamIMM.h>
#include <immslam/slam/COnePointRansac.h>
#include <immslam/slam/measurement.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using namespace immslam;
using namespace immslam::slam;

namespace
{
/** A synthetic 1-point RANSAC problem with a known answer.
 *
 * The state is a camera block (13, untouched) and n XYZ points in the camera frame at depths 2-3.
 * The prior says the whole map may be shifted sideways by a common unknown d = (dx, dy, 0)
 * (std 0.1, about 7-10 px at these depths), each point by 1e-4 more on its own. The truth is
 * such a shift: inliers are measured at proj(p + d) plus a noise bounded by 0.3 px per axis;
 * outliers 8-30 px away from it in a random direction.
 *
 * Why the answer is known: a hypothesis from one inlier recovers d to within the noise scaled by
 * the depth ratio (<= 1.5), so every inlier is predicted within 0.42 * 1.5 + 0.42 < 1.1 px of its
 * measurement (the threshold is 2 px), and every outlier at least 8 - 0.64 > 7 px away. A
 * hypothesis from an outlier shifts the map by >= 8 * 2/3 px at the others: it supports no inlier.
 * So the best hypothesis is any inlier's, and its support is exactly the inlier set. */
struct TRansacProblem
{
  camera::CCameraModel::Ptr cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  VecX x;
  MatX P;
  std::vector<TFeature> feats;
  std::vector<TCandidate> cands;
  std::vector<int> inliers;  ///< the known answer, ascending
  double sigmaPixel = 0.2;

  TRansacProblem(int n, int nOutliers, unsigned seed)
  {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> U(0, 1);
    std::normal_distribution<double> g;
    const int dim = 13 + 3 * n;
    x = VecX::Zero(dim);
    x[3] = 1;
    // Prior: sigma_d^2 B B^T (common sideways shift) + 1e-8 I.
    MatX B = MatX::Zero(dim, 2);
    for (int k = 0; k < n; ++k) B.block<2, 2>(13 + 3 * k, 0).setIdentity();
    P = 0.01 * B * B.transpose() + 1e-8 * MatX::Identity(dim, dim);
    const Vec3 d(0.1 * g(rng), 0.1 * g(rng), 0.0);
    // Which candidates are outliers: nOutliers distinct indices.
    std::vector<int> idx(n);
    for (int k = 0; k < n; ++k) idx[k] = k;
    std::shuffle(idx.begin(), idx.end(), rng);
    std::vector<char> outlier(n, 0);
    for (int k = 0; k < nOutliers; ++k) outlier[idx[k]] = 1;
    for (int k = 0; k < n; ++k)
    {
      const Vec2 uv(40 + 240 * U(rng), 40 + 160 * U(rng));
      const double depth = 2 + U(rng);
      const Vec3 b = cam->unproject(uv).unitVector();
      const Vec3 p = b * (depth / b.z());
      x.segment<3>(13 + 3 * k) = p;
      TFeature f;
      f.id = k;
      f.kind = EFeatureKind::XYZ;
      f.offset = 13 + 3 * k;
      feats.push_back(f);
      Vec2 zTrue;
      EXPECT_TRUE(cam->project(p + d, zTrue));
      Vec2 z;
      if (outlier[k])
      {
        const double a = 2 * M_PI * U(rng), rad = 8 + 22 * U(rng);
        z = zTrue + rad * Vec2(std::cos(a), std::sin(a));
      }
      else
      {
        z = zTrue + Vec2(0.6 * U(rng) - 0.3, 0.6 * U(rng) - 0.3);
        inliers.push_back(k);
      }
      TCandidate c;
      c.feature = k;
      c.z = z;
      EXPECT_TRUE(predictMeasurement(*cam, x, f, c.h, &c.J_feat));
      c.S = innovationCovariance(P.block<3, 3>(f.offset, f.offset), c.J_feat, sigmaPixel);
      cands.push_back(c);
    }
  }

  std::vector<int> run(const COnePointRansac& ransac, std::mt19937& rng, int* nHyp) const
  {
    return ransac.lowInnovationInliers(
        *cam, x, [this](int off, int len) { return MatX(P.middleCols(off, len)); }, feats, cands, rng, nHyp);
  }
};

/** The documented adaptive count for inlier ratio eps and success probability p, whole hypotheses:
 * the loop runs while tried < log(1 - p) / log(1 - eps). */
int adaptiveCount(double p, double eps)
{
  return eps >= 1.0 ? 1 : static_cast<int>(std::ceil(std::log(1 - p) / std::log(1 - eps)));
}
}  // namespace

TEST(OnePointRansac, RecoversTheExactInlierSet)
{
  const COnePointRansac ransac;  // defaults: 2 px, p = 0.99, at most 200 hypotheses
  for (const int nOut : {6, 10})  // 30 % and 50 % of 20 matches
    for (unsigned seed = 1; seed <= 40; ++seed)
    {
      const TRansacProblem pb(20, nOut, seed);
      ASSERT_EQ(static_cast<int>(pb.inliers.size()), 20 - nOut);
      std::mt19937 rng(1000 + seed);
      int nHyp = 0;
      const std::vector<int> got = pb.run(ransac, rng, &nHyp);
      ASSERT_EQ(got, pb.inliers) << nOut << " outliers, seed " << seed;
    }
}

TEST(OnePointRansac, AdaptiveHypothesisCountFollowsTheFormula)
{
  // n_hyp = log(1 - p) / log(1 - eps), p = 0.99: eps = 0.7 -> 3.82 (4 hypotheses), eps = 0.5 -> 6.64 (7).
  const COnePointRansac ransac;
  const double p = ransac.options().success_probability;
  EXPECT_EQ(adaptiveCount(p, 0.7), 4);
  EXPECT_EQ(adaptiveCount(p, 0.5), 7);
  for (const int nOut : {6, 10})
  {
    const double eps = (20.0 - nOut) / 20.0;
    double sum = 0;
    const int seeds = 200;
    for (unsigned seed = 1; seed <= seeds; ++seed)
    {
      const TRansacProblem pb(20, nOut, seed);
      std::mt19937 rng(5000 + seed);
      // The draw (1-based) that first picks an inlier, from a copy of the same stream: until then
      // the best support is an outlier's (1 or 2 of 20 matches: the count is then >= 43), after it
      // the count is the formula's for the true ratio.
      std::mt19937 probe = rng;
      std::uniform_int_distribution<int> pick(0, 19);
      int first = 0;
      while (true)
      {
        ++first;
        const int c = pick(probe);
        if (std::binary_search(pb.inliers.begin(), pb.inliers.end(), c)) break;
      }
      ASSERT_LT(first, 40) << "seed " << seed;  // precondition of the rule above
      int nHyp = 0;
      const auto got = pb.run(ransac, rng, &nHyp);
      ASSERT_EQ(got, pb.inliers) << "seed " << seed;
      EXPECT_EQ(nHyp, std::max(first, adaptiveCount(p, eps))) << nOut << " outliers, seed " << seed;
      sum += nHyp;
    }
    // The mean of max(K, N), K geometric(eps), N the formula's count: N + (1 - eps)^N / eps.
    const int N = adaptiveCount(p, eps);
    const double expected = N + std::pow(1 - eps, N) / eps;
    EXPECT_NEAR(sum / seeds, expected, 0.1 * expected) << nOut << " outliers";
  }
  // No outlier: eps = 1, one hypothesis.
  const TRansacProblem clean(20, 0, 3);
  std::mt19937 rng(3);
  int nHyp = 0;
  EXPECT_EQ(clean.run(ransac, rng, &nHyp), clean.inliers);
  EXPECT_EQ(nHyp, 1);
}

TEST(OnePointRansac, HighInnovationRescue)
{
  // One model, no adaptive noise (sigma 1 px), camera at rest in the filter's prior mean; the true
  // camera moves 0.05 sideways (x) between frames 0 and 1. Twelve "known" features with a tight depth
  // prior at their true depth (rho = 1 +- 0.01), and two features with the wide prior rho = 1 +- 1 at
  // true rho = 0.5:
  //  - R, measured exactly: its single-point prediction (rho = 1) is 10 / b_z px off along x, its
  //    true shift 5 / b_z px -> innovation ~5 px > 2 px (not a low-innovation inlier); after the
  //    update the epipolar (x) direction keeps the depth's spread, (10 px x sigma_rho 1)^2 = 100 px^2:
  //    chi2 ~ 25 / 101 << 9.21 (rescue gate, p = 0.99): rescued.
  //  - N, measured 8 px off its true pixel across the epipolar line (y): chi2 >= 64 / (1 + small)
  //    > 9.21: rejected.
  const auto cam = camera::makeCameraModel("pinhole", 320, 240, {200, 200, 160, 120});
  CMonoSlamIMM::TOptions o;
  o.num_threads = 1;
  o.adaptive_pixel_noise = false;
  o.sigma_pixel = 1.0;
  o.init_linear_velocity_std_px = 20;  // 0.1 per frame: the 0.05 step is 0.5 sigma
  o.init_angular_velocity_std_px = 0.5;
  o.convert_to_xyz = false;
  o.relocalise = false;
  TIMMBankOptions b;
  b.models = "general:0.5";
  CMonoSlamIMM slam(o, b, COnePointRansac::TOptions(), cam);
  slam.processMeasurements(0.0, {});
  std::vector<Vec2> uv;
  std::vector<std::pair<double, double>> prior;
  std::vector<double> rhoTrue;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 3; ++j)
    {
      uv.emplace_back(50 + 70 * i, 50 + 70 * j);
      prior.emplace_back(1.0, 0.01);
      rhoTrue.push_back(1.0);
    }
  uv.emplace_back(130, 90);  // R
  uv.emplace_back(200, 150);  // N
  for (int k = 0; k < 2; ++k) prior.emplace_back(1.0, 1.0), rhoTrue.push_back(0.5);
  const auto ids = slam.addFeaturesAt(cv::Mat(), uv, prior);
  ASSERT_EQ(ids.size(), uv.size());
  const std::int64_t idR = ids[12], idN = ids[13];
  const Vec3 t(0.05, 0, 0);
  std::vector<std::pair<std::int64_t, Vec2>> z;
  for (std::size_t k = 0; k < uv.size(); ++k)
  {
    const Vec3 pW = cam->unproject(uv[k]).unitVector() / rhoTrue[k];
    Vec2 m;
    ASSERT_TRUE(cam->project(pW - t, m));
    if (ids[k] == idN) m.y() += 8.0;
    z.emplace_back(ids[k], m);
  }
  const TFrameReport& rep = slam.processMeasurements(1 / 30.0, z, true);
  EXPECT_EQ(rep.nFound, 14);
  EXPECT_EQ(rep.nLowInnovation, 12);
  EXPECT_EQ(rep.nRescued, 1);
  EXPECT_EQ(rep.nRejected, 1);
  for (const auto& rec : rep.searches)
  {
    ASSERT_TRUE(rec.found) << "feature " << rec.id;
    const auto expected = rec.id == idR   ? TSearchRecord::EStatus::RescuedInlier
                          : rec.id == idN ? TSearchRecord::EStatus::Rejected
                                          : TSearchRecord::EStatus::LowInnovationInlier;
    EXPECT_EQ(static_cast<int>(rec.status), static_cast<int>(expected)) << "feature " << rec.id;
  }
  // The camera moved by t: the fused estimate has it (the known features fix it).
  EXPECT_LT((slam.cameraPosition() - t).norm(), 0.005) << slam.cameraPosition().transpose();
}
