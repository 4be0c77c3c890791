/* Tests: sparse Jacobian algebra and the EKF update against the dense textbook formulas. */
#include <gtest/gtest.h>
#include <immslam/bayes/ekf_update.h>
#include <immslam/math/gaussian.h>

#include <Eigen/Dense>
#include <random>

using namespace immslam;
using namespace immslam::bayes;

namespace
{
MatX randomSpd(int n, std::mt19937& rng)
{
  std::normal_distribution<double> g;
  MatX A(n, n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) A(i, j) = g(rng);
  return A * A.transpose() + 0.1 * MatX::Identity(n, n);
}
MatX randomMat(int r, int c, std::mt19937& rng)
{
  std::normal_distribution<double> g;
  MatX A(r, c);
  for (int i = 0; i < r; ++i)
    for (int j = 0; j < c; ++j) A(i, j) = g(rng);
  return A;
}
/** H of k point measurements (2 rows each) on a 7-parameter camera and k 6-parameter features. */
CSparseJacobian randomCameraFeatureJacobian(int k, int n, std::mt19937& rng)
{
  CSparseJacobian H(2 * k, n);
  for (int f = 0; f < k; ++f)
  {
    H.addBlock(2 * f, 0, randomMat(2, 7, rng));
    H.addBlock(2 * f, 7 + 6 * f, randomMat(2, 6, rng));
  }
  return H;
}
}  // namespace

TEST(SparseJacobian, MatchesDense)
{
  std::mt19937 rng(1);
  CSparseJacobian H(4, 20);
  H.addBlock(0, 0, randomMat(2, 7, rng));
  H.addBlock(0, 13, randomMat(2, 6, rng));
  H.addBlock(2, 0, randomMat(2, 7, rng));
  H.addBlock(2, 7, randomMat(2, 3, rng));
  const MatX Hd = H.toDense();
  const MatX P = randomSpd(20, rng);
  EXPECT_LT((H.timesTransposedBy(P) - P * Hd.transpose()).norm(), 1e-10);
  EXPECT_LT((H.times(P) - Hd * P).norm(), 1e-10);
  const VecX x = randomMat(20, 1, rng);
  EXPECT_LT((H.timesVector(x) - Hd * x).norm(), 1e-12);
  EXPECT_THROW(H.addBlock(3, 0, randomMat(2, 2, rng)), std::out_of_range);
}

TEST(EkfUpdate, MatchesTextbookKalmanUpdate)
{
  std::mt19937 rng(2);
  const int n = 25;
  const CSparseJacobian H = randomCameraFeatureJacobian(3, n, rng);
  const MatX Hd = H.toDense();
  VecX x = randomMat(n, 1, rng);
  MatX P = randomSpd(n, rng);
  const VecX nu = randomMat(6, 1, rng);
  const VecX R = VecX::Constant(6, 0.5);

  const MatX S = Hd * P * Hd.transpose() + MatX(R.asDiagonal());
  const MatX K = P * Hd.transpose() * S.inverse();
  const VecX xRef = x + K * nu;
  const MatX PRef = (MatX::Identity(n, n) - K * Hd) * P;
  const double llRef = math::gaussianLogLikelihood(nu, S);

  const auto res = ekfUpdate(x, P, H, nu, R);
  ASSERT_TRUE(res.ok);
  EXPECT_LT((x - xRef).norm(), 1e-9);
  EXPECT_LT((P - PRef).norm(), 1e-8 * PRef.norm());
  EXPECT_EQ(P, P.transpose());  // exactly symmetric
  EXPECT_NEAR(res.logLikelihood, llRef, 1e-9);
  EXPECT_NEAR(res.nis, nu.dot(S.inverse() * nu), 1e-9);
  EXPECT_EQ(res.dim, 6);
}

TEST(EkfUpdate, LogLikelihoodOnlyMatchesTheUpdateAndLeavesTheStateAlone)
{
  std::mt19937 rng(4);
  const int n = 31;
  CSparseJacobian H(8, n);
  for (int k = 0; k < 4; ++k) H.addBlock(2 * k, 7 + 6 * k, randomMat(2, 6, rng));
  VecX x = randomMat(n, 1, rng);
  MatX P = randomSpd(n, rng);
  const VecX nu = randomMat(8, 1, rng);
  const VecX R = VecX::Constant(8, 0.3);
  const auto only = ekfLogLikelihood(P, H, nu, R);
  const auto full = ekfUpdate(x, P, H, nu, R);
  ASSERT_TRUE(only.ok && full.ok);
  EXPECT_NEAR(only.logLikelihood, full.logLikelihood, 1e-9 * std::abs(full.logLikelihood));
  EXPECT_NEAR(only.nis, full.nis, 1e-9 * full.nis);
  EXPECT_EQ(only.dim, 8);
  EXPECT_FALSE(ekfLogLikelihood(MatX::Zero(n, n), H, nu, VecX::Zero(8)).ok);
}

TEST(EkfUpdate, ReusingTheLikelihoodsFactorsGivesBitwiseTheSameUpdate)
{
  std::mt19937 rng(5);
  const int n = 43;
  const CSparseJacobian H = randomCameraFeatureJacobian(5, n, rng);
  const VecX x0 = randomMat(n, 1, rng);
  const MatX P0 = randomSpd(n, rng);
  const VecX nu = randomMat(10, 1, rng);
  const VecX R = VecX::Constant(10, 0.7);

  VecX xA = x0, xB = x0;
  MatX PA = P0, PB = P0;
  const auto plain = ekfUpdate(xA, PA, H, nu, R);
  TInnovationFactors f;
  const auto lik = ekfLogLikelihood(PB, H, nu, R, nullptr, &f);
  ASSERT_TRUE(f.ok);
  EXPECT_EQ(f.PHt.rows(), n);
  EXPECT_EQ(f.PHt.cols(), 10);
  const auto reused = ekfUpdate(xB, PB, H, nu, R, &f);
  ASSERT_TRUE(plain.ok && lik.ok && reused.ok);
  EXPECT_FALSE(f.ok);  // consumed: P has changed
  EXPECT_EQ(xA, xB);
  EXPECT_EQ(PA, PB);
  EXPECT_EQ(plain.logLikelihood, reused.logLikelihood);
  EXPECT_EQ(plain.nis, reused.nis);
  EXPECT_EQ(lik.logLikelihood, plain.logLikelihood);

  // Consumed factors are not reused: a second update with them recomputes from the new P.
  VecX xC = xA, xD = xA;
  MatX PC = PA, PD = PA;
  ekfUpdate(xC, PC, H, nu, R);
  ekfUpdate(xD, PD, H, nu, R, &f);
  EXPECT_EQ(PC, PD);
  EXPECT_EQ(xC, xD);

  // A failed factorisation is never kept as usable.
  TInnovationFactors bad;
  EXPECT_FALSE(ekfLogLikelihood(MatX::Zero(n, n), H, nu, VecX::Zero(10), nullptr, &bad).ok);
  EXPECT_FALSE(bad.ok);
}

TEST(EkfUpdate, RejectsNonPositiveInnovationCovariance)
{
  std::mt19937 rng(3);
  VecX x = VecX::Zero(3);
  MatX P = MatX::Zero(3, 3);
  CSparseJacobian H(1, 3);
  H.addBlock(0, 0, MatX::Ones(1, 3));
  const auto res = ekfUpdate(x, P, H, VecX::Ones(1), VecX::Zero(1));
  EXPECT_FALSE(res.ok);
  EXPECT_TRUE(x.isZero());
}

TEST(EkfUpdate, NisIsChiSquareOnLinearGaussianData)
{
  // Monte Carlo: for a correct linear-Gaussian model the NIS averages to the measurement dimension.
  std::mt19937 rng(4);
  std::normal_distribution<double> g;
  const int n = 6, m = 2, N = 4000;
  double sumNis = 0;
  for (int t = 0; t < N; ++t)
  {
    MatX P = MatX::Identity(n, n) * 0.3;
    const VecX xTrue = (randomMat(n, 1, rng) * std::sqrt(0.3));
    VecX x = VecX::Zero(n);
    CSparseJacobian H(m, n);
    H.addBlock(0, 0, MatX::Identity(2, 2));
    H.addBlock(0, 4, 0.5 * MatX::Identity(2, 2));
    VecX z = H.timesVector(xTrue);
    z[0] += g(rng) * 0.2;
    z[1] += g(rng) * 0.2;
    const auto res = ekfUpdate(x, P, H, VecX(z - H.timesVector(x)), VecX::Constant(m, 0.04));
    sumNis += res.nis;
  }
  EXPECT_NEAR(sumNis / N, 2.0, 0.15);
}
