/* Tests: the generic IMM against a textbook implementation, identical models = one filter,
 * probabilities valid, mixing keeps covariances symmetric positive definite. */
#include <gtest/gtest.h>
#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/bayes/ekf_update.h>
#include <immslam/math/gaussian.h>
#include <immslam/math/parallel.h>

#include <Eigen/Dense>
#include <random>

using namespace immslam;
using namespace immslam::bayes;

namespace
{
/** Textbook IMM step (Bar-Shalom, Li & Kirubarajan, ch. 11), dense, written independently of the library. */
struct TextbookImm
{
  std::vector<VecX> x;
  std::vector<MatX> P;
  VecX mu;
  MatX pi;
  void step(const std::vector<MatX>& F, const std::vector<MatX>& Q, const MatX& H, const MatX& R, const VecX& z)
  {
    const int r = static_cast<int>(mu.size());
    VecX c = VecX::Zero(r);
    for (int i = 0; i < r; ++i)
      for (int j = 0; j < r; ++j) c[i] += pi(j, i) * mu[j];
    std::vector<VecX> x0(r);
    std::vector<MatX> P0(r);
    for (int i = 0; i < r; ++i)
    {
      x0[i] = VecX::Zero(x[0].size());
      for (int j = 0; j < r; ++j) x0[i] += pi(j, i) * mu[j] / c[i] * x[j];
      P0[i] = MatX::Zero(x[0].size(), x[0].size());
      for (int j = 0; j < r; ++j)
      {
        const VecX d = x[j] - x0[i];
        P0[i] += pi(j, i) * mu[j] / c[i] * (P[j] + d * d.transpose());
      }
    }
    VecX L(r);
    for (int i = 0; i < r; ++i)
    {
      const VecX xp = F[i] * x0[i];
      const MatX Pp = F[i] * P0[i] * F[i].transpose() + Q[i];
      const MatX S = H * Pp * H.transpose() + R;
      const MatX K = Pp * H.transpose() * S.inverse();
      const VecX nu = z - H * xp;
      x[i] = xp + K * nu;
      P[i] = (MatX::Identity(xp.size(), xp.size()) - K * H) * Pp;
      L[i] = std::exp(-0.5 * nu.dot(S.inverse() * nu)) / std::sqrt((2 * M_PI * S).determinant());
    }
    VecX m = c.cwiseProduct(L);
    mu = m / m.sum();
  }
};

void runLibraryStep(CIMMEstimator& imm, const std::vector<MatX>& F, const std::vector<MatX>& Q, const MatX& H,
                    const MatX& R, const VecX& z, math::CThreadPool* pool)
{
  imm.mix(pool);
  VecX ll(imm.numModels());
  for (int i = 0; i < imm.numModels(); ++i)
  {
    auto& g = imm.mode(i);
    g.x = F[i] * g.x;
    g.P = F[i] * g.P * F[i].transpose() + Q[i];
    CSparseJacobian Hs(static_cast<int>(H.rows()), static_cast<int>(H.cols()));
    Hs.addBlock(0, 0, H);
    const auto res = ekfUpdate(g.x, g.P, Hs, VecX(z - H * g.x), VecX(R.diagonal()));
    ll[i] = res.logLikelihood;
  }
  imm.updateProbabilities(ll);
}

MatX cvModel(double dt)
{
  MatX F = MatX::Identity(4, 4);
  F(0, 2) = F(1, 3) = dt;
  return F;
}
MatX cvNoise(double q)
{
  MatX Q = MatX::Zero(4, 4);
  Q.diagonal() << q / 3, q / 3, q, q;
  Q(0, 2) = Q(2, 0) = Q(1, 3) = Q(3, 1) = q / 2;
  return Q;
}
}  // namespace

TEST(IMM, MatchesTextbookOnLinearToyProblemStepByStep)
{
  // 3 models: stationary (F zeroes velocity), slow and fast constant velocity; a target that stops and goes.
  std::vector<MatX> F = {cvModel(1), cvModel(1), cvModel(1)};
  F[0](0, 2) = F[0](1, 3) = 0;
  F[0](2, 2) = F[0](3, 3) = 0;
  std::vector<MatX> Q = {MatX::Identity(4, 4) * 1e-4, cvNoise(0.01), cvNoise(1.0)};
  MatX H = MatX::Zero(2, 4);
  H(0, 0) = H(1, 1) = 1;
  const MatX R = MatX::Identity(2, 2) * 0.25;
  MatX pi(3, 3);
  pi << 0.9, 0.05, 0.05, 0.05, 0.9, 0.05, 0.05, 0.05, 0.9;
  const VecX mu0 = VecX::Constant(3, 1.0 / 3);

  CIMMEstimator imm(pi, mu0, 0.0);
  const VecX x0 = VecX::Zero(4);
  const MatX P0 = MatX::Identity(4, 4);
  imm.setAllModes(x0, P0);
  TextbookImm ref{{x0, x0, x0}, {P0, P0, P0}, mu0, pi};
  math::CThreadPool pool(2);

  std::mt19937 rng(5);
  std::normal_distribution<double> g(0, 0.5);
  Eigen::Vector2d pos(0, 0), vel(0, 0);
  for (int k = 0; k < 60; ++k)
  {
    vel = (k > 20 && k < 40) ? Eigen::Vector2d(1.0, 0.5) : Eigen::Vector2d(0, 0);
    pos += vel;
    const VecX z = pos + Eigen::Vector2d(g(rng), g(rng));
    ref.step(F, Q, H, R, z);
    runLibraryStep(imm, F, Q, H, R, z, (k % 2) ? &pool : nullptr);
    ASSERT_LT((imm.probabilities() - ref.mu).norm(), 1e-9) << "step " << k;
    for (int i = 0; i < 3; ++i)
    {
      ASSERT_LT((imm.mode(i).x - ref.x[i]).norm(), 1e-8) << "step " << k;
      ASSERT_LT((imm.mode(i).P - ref.P[i]).norm(), 1e-8) << "step " << k;
    }
  }
  // The models are recognised: moving phase gave the moving models the mass.
  EXPECT_GT(imm.probabilities()[0], 0.5);  // stopped again at the end
}

TEST(IMM, IdenticalModelsGiveTheSingleFilter)
{
  const int r = 4;
  std::vector<MatX> F(r, cvModel(1)), Q(r, cvNoise(0.1));
  MatX H = MatX::Zero(2, 4);
  H(0, 0) = H(1, 1) = 1;
  const MatX R = MatX::Identity(2, 2) * 0.1;
  MatX pi = MatX::Constant(r, r, 0.1 / (r - 1));
  pi.diagonal().setConstant(0.9);
  CIMMEstimator imm(pi, VecX::Constant(r, 1.0 / r), 1e-6);
  CIMMEstimator single(MatX::Identity(1, 1), VecX::Ones(1));
  imm.setAllModes(VecX::Zero(4), MatX::Identity(4, 4));
  single.setAllModes(VecX::Zero(4), MatX::Identity(4, 4));
  std::mt19937 rng(6);
  std::normal_distribution<double> g;
  for (int k = 0; k < 30; ++k)
  {
    const VecX z = Eigen::Vector2d(k * 0.3 + g(rng) * 0.3, g(rng) * 0.3);
    runLibraryStep(imm, F, Q, H, R, z, nullptr);
    runLibraryStep(single, {F[0]}, {Q[0]}, H, R, z, nullptr);
    VecX xf;
    MatX Pf;
    imm.combine(imm.probabilities(), xf, &Pf);
    EXPECT_LT((xf - single.mode(0).x).norm(), 1e-10);
    EXPECT_LT((Pf - single.mode(0).P).norm(), 1e-10);
    EXPECT_LT((imm.probabilities() - VecX::Constant(r, 1.0 / r)).norm(), 1e-12);
  }
}

TEST(IMM, ProbabilitiesValidAndFloored)
{
  MatX pi(2, 2);
  pi << 0.95, 0.05, 0.05, 0.95;
  CIMMEstimator imm(pi, VecX::Constant(2, 0.5), 1e-3);
  imm.setAllModes(VecX::Zero(1), MatX::Identity(1, 1));
  for (int k = 0; k < 50; ++k)
  {
    imm.mix();
    imm.updateProbabilities(Eigen::Vector2d(0.0, -1e6));  // model 1 hopeless
    const VecX& mu = imm.probabilities();
    EXPECT_NEAR(mu.sum(), 1.0, 1e-12);
    EXPECT_GE(mu.minCoeff(), 1e-3 - 1e-15);
  }
  imm.mix();
  imm.updateProbabilities(Eigen::Vector2d(-INFINITY, NAN));  // nothing usable: keep the prediction
  EXPECT_LT((imm.probabilities() - imm.predictedProbabilities()).norm(), 1e-15);
}

TEST(IMM, RejectsBadTransitionMatrices)
{
  MatX pi(2, 2);
  pi << 0.9, 0.2, 0.1, 0.9;
  EXPECT_THROW(CIMMEstimator(pi, VecX::Constant(2, 0.5)), std::invalid_argument);
  pi << 1.1, -0.1, 0.1, 0.9;
  EXPECT_THROW(CIMMEstimator(pi, VecX::Constant(2, 0.5)), std::invalid_argument);
  EXPECT_THROW(CIMMEstimator(MatX::Identity(2, 2), VecX::Constant(3, 1.0 / 3)), std::invalid_argument);
}

TEST(IMM, MixingKeepsCovariancesSymmetricPositiveDefinite)
{
  std::mt19937 rng(8);
  std::normal_distribution<double> g;
  const int r = 7, n = 77;  // not a multiple of the tile width
  MatX pi = MatX::Constant(r, r, 0.02 / (r - 1));
  pi.diagonal().setConstant(0.98);
  VecX mu(r);
  for (int i = 0; i < r; ++i) mu[i] = 0.01 + std::abs(g(rng));
  mu /= mu.sum();
  CIMMEstimator imm(pi, mu);
  for (int i = 0; i < r; ++i)
  {
    MatX A(n, n);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) A(a, b) = g(rng);
    VecX x(n);
    for (int a = 0; a < n; ++a) x[a] = g(rng);
    imm.mode(i) = TGaussian{x, A * A.transpose() / n + 1e-3 * MatX::Identity(n, n)};
  }
  // Reference mixing, dense.
  std::vector<TGaussian> before;
  for (int i = 0; i < r; ++i) before.push_back(imm.mode(i));
  math::CThreadPool pool(2);
  imm.mix(&pool);
  for (int i = 0; i < r; ++i)
  {
    const MatX& P = imm.mode(i).P;
    EXPECT_EQ(P, P.transpose());
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(P).eigenvalues().minCoeff(), 0.0);
    VecX xr = VecX::Zero(n);
    for (int j = 0; j < r; ++j) xr += imm.mixingWeights()(j, i) * before[j].x;
    MatX Pr = MatX::Zero(n, n);
    for (int j = 0; j < r; ++j)
      Pr += imm.mixingWeights()(j, i) * (before[j].P + (before[j].x - xr) * (before[j].x - xr).transpose());
    EXPECT_LT((imm.mode(i).x - xr).norm(), 1e-12);
    EXPECT_LT((P - Pr).norm(), 1e-10);
    EXPECT_NEAR(imm.mixingWeights().col(i).sum(), 1.0, 1e-12);
  }
  // The combined block equals the block of the full combination.
  VecX xf;
  MatX Pf;
  imm.combine(imm.predictedProbabilities(), xf, &Pf, &pool);
  EXPECT_LT((imm.combinedBlock(imm.predictedProbabilities(), xf, 10, 6) - Pf.block(10, 10, 6, 6)).norm(), 1e-12);
  EXPECT_LT((imm.combinedColumns(imm.predictedProbabilities(), xf, 10, 6) - Pf.middleCols(10, 6)).norm(), 1e-12);
  EXPECT_LT((Pf - Pf.transpose()).norm(), 1e-12);
}
