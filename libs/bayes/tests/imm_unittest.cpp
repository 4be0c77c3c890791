/* Tests: the generic IMM against a textbook implementation, identical models = one filter,
 * probabilities valid, mixing keeps covariances symmetric positive definite and equals the dense
 * textbook mixing for structured, general, sparse Markov matrices and zero probabilities, bitwise
 * the same with and without a thread pool. */
#include <gtest/gtest.h>
#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/bayes/ekf_update.h>
#include <immslam/math/gaussian.h>
#include <immslam/math/parallel.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <string>
#include <utility>

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
  // An asymmetric Markov matrix (rows sum to 1, columns do not): a transposed use of it fails.
  MatX pi(3, 3);
  pi << 0.9, 0.07, 0.03, 0.1, 0.85, 0.05, 0.02, 0.18, 0.8;
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
  // Reference mixing, dense, with the weights mu_{j|i} = pi_ji mu_j / c_i, c_i = sum_j pi_ji mu_j
  // computed here (not the class's mixingWeights(), which is checked against them).
  std::vector<TGaussian> before;
  for (int i = 0; i < r; ++i) before.push_back(imm.mode(i));
  MatX W(r, r);
  for (int i = 0; i < r; ++i)
  {
    double c = 0;
    for (int j = 0; j < r; ++j) c += pi(j, i) * mu[j];
    for (int j = 0; j < r; ++j) W(j, i) = pi(j, i) * mu[j] / c;
  }
  math::CThreadPool pool(2);
  imm.mix(&pool);
  EXPECT_LT((imm.mixingWeights() - W).cwiseAbs().maxCoeff(), 1e-15);
  for (int i = 0; i < r; ++i)
  {
    const MatX& P = imm.mode(i).P;
    EXPECT_EQ(P, P.transpose());
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(P).eigenvalues().minCoeff(), 0.0);
    VecX xr = VecX::Zero(n);
    for (int j = 0; j < r; ++j) xr += W(j, i) * before[j].x;
    MatX Pr = MatX::Zero(n, n);
    for (int j = 0; j < r; ++j) Pr += W(j, i) * (before[j].P + (before[j].x - xr) * (before[j].x - xr).transpose());
    EXPECT_LT((imm.mode(i).x - xr).norm(), 1e-12);
    EXPECT_LT((P - Pr).norm(), 1e-10);
    EXPECT_NEAR(W.col(i).sum(), 1.0, 1e-12);
  }
  // The combined block equals the block of the full combination.
  VecX xf;
  MatX Pf;
  imm.combine(imm.predictedProbabilities(), xf, &Pf, &pool);
  EXPECT_LT((imm.combinedBlock(imm.predictedProbabilities(), xf, 10, 6) - Pf.block(10, 10, 6, 6)).norm(), 1e-12);
  EXPECT_LT((imm.combinedColumns(imm.predictedProbabilities(), xf, 10, 6) - Pf.middleCols(10, 6)).norm(), 1e-12);
  EXPECT_LT((Pf - Pf.transpose()).norm(), 1e-12);
}

namespace
{
/** r modes of dimension n: means around a common offset (as the modes of a bank that differ
 * slightly), symmetric positive definite covariances of different scales. */
std::vector<TGaussian> randomModes(int r, int n, unsigned seed)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> g;
  VecX base(n);
  for (int a = 0; a < n; ++a) base[a] = 10 * g(rng);
  std::vector<TGaussian> modes;
  for (int i = 0; i < r; ++i)
  {
    MatX A(n, n);
    for (int a = 0; a < n; ++a)
      for (int b = 0; b < n; ++b) A(a, b) = g(rng);
    MatX P = (1.0 + 0.3 * i) * A * A.transpose() / n + 1e-3 * MatX::Identity(n, n);
    P = 0.5 * (P + P.transpose()).eval();
    VecX x = base;
    for (int a = 0; a < n; ++a) x[a] += 0.3 * g(rng);
    modes.push_back(TGaussian{x, P});
  }
  return modes;
}

/** Random row-stochastic matrix with distinct entries (dense Delta: every mode has r own terms). */
MatX randomMarkov(int r, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.05, 1.0);
  MatX pi(r, r);
  for (int j = 0; j < r; ++j)
  {
    for (int i = 0; i < r; ++i) pi(j, i) = u(rng) + (i == j ? 2.0 : 0.0);
    pi.row(j) /= pi.row(j).sum();
  }
  return pi;
}

MatX defaultMarkov(int r, double stay)
{
  MatX pi = MatX::Constant(r, r, (1.0 - stay) / (r - 1));
  pi.diagonal().setConstant(stay);
  return pi;
}

/** The textbook mixing (Fig. 2 step 1), dense, written independently of the library. */
void textbookMix(const MatX& pi, const VecX& mu, const std::vector<TGaussian>& in, std::vector<TGaussian>& out)
{
  const int r = static_cast<int>(mu.size());
  const auto n = in[0].x.size();
  out.assign(r, TGaussian{});
  for (int i = 0; i < r; ++i)
  {
    double c = 0;
    for (int j = 0; j < r; ++j) c += pi(j, i) * mu[j];
    if (c <= 0)
    {
      out[i] = in[i];
      continue;
    }
    out[i].x = VecX::Zero(n);
    for (int j = 0; j < r; ++j) out[i].x += pi(j, i) * mu[j] / c * in[j].x;
    out[i].P = MatX::Zero(n, n);
    for (int j = 0; j < r; ++j)
    {
      const VecX d = in[j].x - out[i].x;
      out[i].P += pi(j, i) * mu[j] / c * (in[j].P + d * d.transpose());
    }
  }
}

/** mix() with no pool, a 1-thread and a 2-thread pool: bitwise equal, equal to the textbook to
 * 1e-12 relative, exactly symmetric, positive definite. The 2-thread estimator first mixes modes of
 * another dimension (its buffers are reused at a new size). */
void checkMixing(const MatX& pi, const VecX& mu, const std::vector<TGaussian>& modes, const std::string& what)
{
  SCOPED_TRACE(what);
  const int r = static_cast<int>(mu.size());
  const auto n = modes[0].x.size();
  std::vector<TGaussian> ref;
  textbookMix(pi, mu, modes, ref);

  math::CThreadPool pool1(1), pool2(2);
  std::vector<std::unique_ptr<CIMMEstimator>> imms;
  for (math::CThreadPool* pool : {static_cast<math::CThreadPool*>(nullptr), &pool1, &pool2})
  {
    imms.push_back(std::make_unique<CIMMEstimator>(pi, mu, 0.0));
    CIMMEstimator& imm = *imms.back();
    if (pool == &pool2)
    {
      const auto other = randomModes(r, static_cast<int>(n) + 21, 99);
      for (int i = 0; i < r; ++i) imm.mode(i) = other[i];
      imm.mix(pool);  // mix() leaves mu as it is: the mix under test sees the same probabilities
      for (int i = 0; i < r; ++i) imm.mode(i) = modes[i];
    }
    else
      for (int i = 0; i < r; ++i) imm.mode(i) = modes[i];
    imm.mix(pool);
  }
  for (int i = 0; i < r; ++i)
  {
    const TGaussian& g = imms[0]->mode(i);
    const double scaleP = ref[i].P.cwiseAbs().maxCoeff(), scaleX = ref[i].x.cwiseAbs().maxCoeff();
    EXPECT_LE((g.x - ref[i].x).cwiseAbs().maxCoeff(), 1e-12 * scaleX) << "mode " << i;
    EXPECT_LE((g.P - ref[i].P).cwiseAbs().maxCoeff(), 1e-12 * scaleP) << "mode " << i;
    EXPECT_TRUE(g.P == g.P.transpose()) << "mode " << i << " not exactly symmetric";
    EXPECT_GT(Eigen::SelfAdjointEigenSolver<MatX>(g.P).eigenvalues().minCoeff(), 0.0) << "mode " << i;
    EXPECT_NEAR(imms[0]->mixingWeights().col(i).sum(), 1.0, 1e-12);
    for (size_t k = 1; k < imms.size(); ++k)
    {
      EXPECT_TRUE(imms[k]->mode(i).x == g.x) << "mode " << i << " run " << k << ": means differ between pools";
      EXPECT_TRUE(imms[k]->mode(i).P == g.P) << "mode " << i << " run " << k << ": covariances differ between pools";
      EXPECT_TRUE(imms[k]->mixingWeights() == imms[0]->mixingWeights());
    }
  }
}

VecX randomProbabilities(int r, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.01, 1.0);
  VecX mu(r);
  for (int i = 0; i < r; ++i) mu[i] = u(rng);
  return mu / mu.sum();
}
}  // namespace

TEST(IMM, MixingEqualsTextbookForTheDefaultMatrix)
{
  VecX mu(7);
  mu << 0.02, 0.03, 0.05, 0.1, 0.2, 0.3, 0.3;
  for (int n : {133, 64, 17, 3})  // 133 = 8 chunks of 16 + 5
    checkMixing(defaultMarkov(7, 0.995), mu, randomModes(7, n, 1 + n), "default 0.995, n = " + std::to_string(n));
  checkMixing(defaultMarkov(7, 0.9), randomProbabilities(7, 2), randomModes(7, 40, 3), "default 0.9");
  // Every row the same: only the common term, every mode gets the same (the combined) Gaussian.
  checkMixing(defaultMarkov(4, 0.25), randomProbabilities(4, 4), randomModes(4, 40, 5), "uniform");
}

TEST(IMM, MixingEqualsTextbookForAGeneralMatrix)
{
  for (int r : {2, 3, 5, 7})
    for (int n : {1, 16, 77})
      checkMixing(randomMarkov(r, 10 + r), randomProbabilities(r, 20 + r), randomModes(r, n, 30 + r + n),
                  "random pi, r = " + std::to_string(r) + ", n = " + std::to_string(n));
}

TEST(IMM, MixingEqualsTextbookWithZerosInTheMatrix)
{
  // Every column has a zero: every beta_i = 0, no common term at all.
  MatX band(4, 4);
  band << 0.9, 0.1, 0, 0, 0.05, 0.9, 0.05, 0, 0, 0.05, 0.9, 0.05, 0, 0, 0.1, 0.9;
  checkMixing(band, randomProbabilities(4, 40), randomModes(4, 77, 41), "banded");
  // Columns 0 and 1 with beta > 0, column 2 with beta = 0.
  MatX mixed(3, 3);
  mixed << 0.8, 0.2, 0.0, 0.1, 0.8, 0.1, 0.1, 0.1, 0.8;
  checkMixing(mixed, randomProbabilities(3, 42), randomModes(3, 50, 43), "some zero columns");
  // Identity: no mixing at all.
  checkMixing(MatX::Identity(3, 3), randomProbabilities(3, 44), randomModes(3, 20, 45), "identity");
  // Two states: switching for sure.
  MatX swap(2, 2);
  swap << 0, 1, 1, 0;
  checkMixing(swap, randomProbabilities(2, 46), randomModes(2, 33, 47), "swap");
}

TEST(IMM, MixingEqualsTextbookForABlockStructuredMatrix)
{
  // The default matrix of the 7-model bank (TIMMBankOptions::transitionMatrix): rows 0-3 (stationary, rotation) have
  // zeros in columns 4-6 (general) and keep the rest on the diagonal. Two supports, two common terms.
  MatX pi = defaultMarkov(7, 0.995);
  for (int j = 0; j < 4; ++j)
  {
    pi.row(j).tail(3).setZero();
    pi(j, j) = 0.0;
    pi(j, j) = 1.0 - pi.row(j).sum();
  }
  VecX mu(7);
  mu << 0.3, 0.2, 0.05, 0.05, 0.1, 0.1, 0.2;
  for (int n : {133, 17})
    checkMixing(pi, mu, randomModes(7, n, 70 + n), "evidence, n = " + std::to_string(n));
  checkMixing(pi, randomProbabilities(7, 72), randomModes(7, 40, 73), "evidence, random mu");
  // The same matrix with its entries perturbed by a few ulps (as an ini's matrix after
  // renormalisation): differences of rounding size are not own terms, the result stays the textbook's.
  MatX noisy = pi;
  for (int j = 0; j < 7; ++j)
    for (int i = 0; i < 7; ++i)
      if (noisy(j, i) > 0 && i != j) noisy(j, i) *= 1.0 + ((i + j) % 3 - 1) * 4e-16;
  checkMixing(noisy, mu, randomModes(7, 50, 74), "evidence with rounding");
}

TEST(IMM, MixingEqualsTextbookWithAZeroProbability)
{
  VecX mu(4);
  mu << 0.5, 0.0, 0.3, 0.2;
  checkMixing(defaultMarkov(4, 0.95), mu, randomModes(4, 45, 50), "mu_1 = 0, default pi");
  checkMixing(randomMarkov(4, 51), mu, randomModes(4, 45, 52), "mu_1 = 0, random pi");
  // c_1 = c_2 = 0: modes 1 and 2 are unreachable and keep their Gaussians exactly.
  MatX pi(3, 3);
  pi << 1, 0, 0, 0, 0.5, 0.5, 0, 0.5, 0.5;
  const VecX mu2 = Eigen::Vector3d(1, 0, 0);
  const auto modes = randomModes(3, 30, 53);
  checkMixing(pi, mu2, modes, "c_i = 0");
  CIMMEstimator imm(pi, mu2, 0.0);
  for (int i = 0; i < 3; ++i) imm.mode(i) = modes[i];
  imm.mix();
  for (int i = 0; i < 3; ++i)
  {
    EXPECT_TRUE(imm.mode(i).x == modes[i].x);
    EXPECT_TRUE(imm.mode(i).P == modes[i].P);
  }
}

namespace
{
/** Mixing with modes 1 and 4 sharing mode 0's covariance and mode 5 mode 2's (aliasMode) against the
 * same mixing of explicit copies: bitwise equal, with and without a pool. */
void checkSharedInputs(const MatX& pi, const VecX& mu, const std::string& what)
{
  const int r = static_cast<int>(mu.size());
  auto modes = randomModes(r, 37, 90);
  std::vector<std::pair<int, int>> shares = {{1, 0}, {4, 0}, {5, 2}};
  for (const auto& [i, s] : shares) modes[i] = modes[s];
  for (const bool withPool : {false, true})
  {
    math::CThreadPool pool(2);
    CIMMEstimator copied(pi, mu, 0.0), shared(pi, mu, 0.0);
    for (int i = 0; i < r; ++i)
    {
      copied.mode(i) = modes[i];
      shared.mode(i) = randomModes(1, 37, 91 + i)[0];  // other values: must not matter after aliasing
    }
    for (int i = 0; i < r; ++i)
      if (std::none_of(shares.begin(), shares.end(), [i](const auto& p) { return p.first == i; }))
        shared.mode(i) = modes[i];
    for (const auto& [i, s] : shares) shared.aliasMode(i, s);
    for (const auto& [i, s] : shares) EXPECT_TRUE(std::as_const(shared).mode(i).P == modes[s].P) << what;
    copied.mix(withPool ? &pool : nullptr);
    shared.mix(withPool ? &pool : nullptr);
    for (int i = 0; i < r; ++i)
    {
      EXPECT_FALSE(shared.isAliased(i)) << what;
      EXPECT_TRUE(shared.mode(i).x == copied.mode(i).x) << what << ", mode " << i;
      EXPECT_TRUE(shared.mode(i).P == copied.mode(i).P) << what << ", mode " << i;
    }
  }
}
}  // namespace

TEST(IMM, MixingOfSharedCovariancesEqualsMixingOfCopies)
{
  VecX mu(7);
  mu << 0.3, 1e-6, 0.2, 0.05, 1e-6, 1e-6, 0.45;
  mu /= mu.sum();
  checkSharedInputs(defaultMarkov(7, 0.995), mu, "default pi (in place)");
  MatX evidence = defaultMarkov(7, 0.995);
  for (int j = 0; j < 4; ++j)
  {
    evidence.row(j).tail(3).setZero();
    evidence(j, j) = 0.0;
    evidence(j, j) = 1.0 - evidence.row(j).sum();
  }
  checkSharedInputs(evidence, mu, "block-structured pi (in place, two supports)");
  checkSharedInputs(randomMarkov(7, 92), mu, "random pi (buffered)");
  // c_1 = 0: mode 1 cannot be entered and keeps what it shares, as its own copy.
  MatX unreachable = defaultMarkov(7, 0.9);
  unreachable.col(1).setZero();
  for (int j = 0; j < 7; ++j) unreachable.row(j) /= unreachable.row(j).sum();
  checkSharedInputs(unreachable, mu, "c_1 = 0");
}

TEST(IMM, MixingIntoTheLowerTriangleOnly)
{
  // lowerOnly: the flagged outputs' lower triangles are the full mixing's, bitwise; the others whole.
  VecX mu(7);
  mu << 0.3, 1e-6, 0.2, 0.05, 1e-6, 1e-6, 0.45;
  mu /= mu.sum();
  const std::vector<char> flags = {1, 0, 1, 1, 0, 1, 1};
  for (const MatX& pi : {defaultMarkov(7, 0.995), randomMarkov(7, 96)})
    for (const bool withPool : {false, true})
    {
      math::CThreadPool pool(2);
      const auto modes = randomModes(7, 41, 97);
      CIMMEstimator whole(pi, mu, 0.0), lower(pi, mu, 0.0);
      for (int i = 0; i < 7; ++i) whole.mode(i) = lower.mode(i) = modes[i];
      whole.mix(withPool ? &pool : nullptr);
      lower.mix(withPool ? &pool : nullptr, 1.0, &flags);
      for (int i = 0; i < 7; ++i)
      {
        EXPECT_TRUE(lower.mode(i).x == whole.mode(i).x);
        const MatX a = lower.mode(i).P.triangularView<Eigen::Lower>(), b = whole.mode(i).P.triangularView<Eigen::Lower>();
        EXPECT_TRUE(a == b) << "mode " << i;
        if (!flags[i])
        {
          EXPECT_TRUE(lower.mode(i).P == whole.mode(i).P) << "mode " << i;
        }
      }
    }
  CIMMEstimator imm(defaultMarkov(3, 0.9), VecX::Constant(3, 1.0 / 3));
  const std::vector<char> wrong = {1, 1};
  EXPECT_THROW(imm.mix(nullptr, 1.0, &wrong), std::invalid_argument);
}

TEST(IMM, WritingToASharedModeGivesTheOthersTheirOwnCopy)
{
  const auto modes = randomModes(3, 12, 95);
  CIMMEstimator imm(defaultMarkov(3, 0.9), VecX::Constant(3, 1.0 / 3));
  for (int i = 0; i < 3; ++i) imm.mode(i) = modes[i];
  imm.aliasMode(1, 0);
  imm.aliasMode(2, 1);  // shares mode 1's source: mode 0
  EXPECT_TRUE(imm.isAliased(1) && imm.isAliased(2));
  EXPECT_TRUE(std::as_const(imm).mode(2).P == modes[0].P);
  imm.mode(0).P(3, 4) += 1.0;  // write access to the source: 1 and 2 keep the old covariance
  EXPECT_FALSE(imm.isAliased(1) || imm.isAliased(2));
  EXPECT_EQ(std::as_const(imm).mode(1).P(3, 4), modes[0].P(3, 4));
  EXPECT_EQ(std::as_const(imm).mode(2).P(3, 4), modes[0].P(3, 4));
  EXPECT_EQ(std::as_const(imm).mode(0).P(3, 4), modes[0].P(3, 4) + 1.0);
  imm.aliasMode(2, 0);
  imm.mode(2).x[0] += 1.0;  // write access to the sharing mode: the source is untouched
  EXPECT_FALSE(imm.isAliased(2));
  EXPECT_TRUE(std::as_const(imm).mode(2).P == std::as_const(imm).mode(0).P);
  EXPECT_EQ(std::as_const(imm).mode(0).x[0] + 1.0, std::as_const(imm).mode(2).x[0]);
  EXPECT_THROW(imm.aliasMode(3, 0), std::out_of_range);
  imm.aliasMode(0, 0);  // itself: nothing
  EXPECT_FALSE(imm.isAliased(0));
}

TEST(IMM, MixingWithOneModelChangesNothing)
{
  const auto modes = randomModes(1, 20, 60);
  CIMMEstimator imm(MatX::Identity(1, 1), VecX::Ones(1));
  imm.mode(0) = modes[0];
  math::CThreadPool pool(2);
  imm.mix(&pool);
  EXPECT_TRUE(imm.mode(0).x == modes[0].x);
  EXPECT_TRUE(imm.mode(0).P == modes[0].P);
  EXPECT_EQ(imm.mixingWeights()(0, 0), 1.0);
  EXPECT_EQ(imm.predictedProbabilities()[0], 1.0);
}

TEST(IMM, TransitionOverAnIntervalIsTheMatrixPower)
{
  const MatX pi = randomMarkov(5, 70);
  CIMMEstimator imm(pi, VecX::Constant(5, 0.2));
  EXPECT_TRUE(imm.transitionOver(0) == MatX::Identity(5, 5));
  EXPECT_TRUE(imm.transitionOver(1) == pi);
  MatX power = MatX::Identity(5, 5);
  for (int n = 1; n <= 9; ++n)
  {
    power = power * pi;
    EXPECT_LE((imm.transitionOver(n) - power).cwiseAbs().maxCoeff(), 1e-14) << "n = " << n;
  }
  // A fraction of a step: the chain that takes the step with that probability.
  const MatX half = 0.5 * (MatX::Identity(5, 5) + pi);
  EXPECT_LE((imm.transitionOver(2.5) - pi * pi * half).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LE((imm.transitionOver(0.25) - (0.75 * MatX::Identity(5, 5) + 0.25 * pi)).cwiseAbs().maxCoeff(), 1e-15);
  // Continuous at whole numbers; stochastic everywhere; a long interval forgets the start (every row
  // tends to the chain's stationary distribution).
  EXPECT_LE((imm.transitionOver(3 - 1e-9) - imm.transitionOver(3)).cwiseAbs().maxCoeff(), 1e-8);
  for (double steps : {0.3, 1.7, 12.0, 1000.0, 1e6})
  {
    const MatX T = imm.transitionOver(steps);
    EXPECT_TRUE((T.array() >= 0).all()) << steps;
    for (int j = 0; j < 5; ++j) EXPECT_NEAR(T.row(j).sum(), 1.0, 1e-14) << steps;
  }
  const MatX longRun = imm.transitionOver(1e6);
  for (int j = 1; j < 5; ++j) EXPECT_LE((longRun.row(j) - longRun.row(0)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_LE((longRun.row(0) * pi - longRun.row(0)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_THROW(imm.transitionOver(-0.5), std::invalid_argument);
  EXPECT_THROW(imm.transitionOver(std::nan("")), std::invalid_argument);
  EXPECT_THROW(imm.transitionOver(HUGE_VAL), std::invalid_argument);
}

TEST(IMM, MixingOverSeveralStepsUsesTheMatrixOfTheInterval)
{
  // A frame that comes 3 steps after the last one (two dropped): predicted probabilities and mixing
  // are those of pi^3, as the textbook mixing with pi^3 gives them.
  const MatX pi = defaultMarkov(7, 0.9);
  const VecX mu = randomProbabilities(7, 71);
  const auto modes = randomModes(7, 40, 72);
  std::vector<TGaussian> ref;
  textbookMix(pi * pi * pi, mu, modes, ref);
  CIMMEstimator imm(pi, mu, 0.0);
  for (int i = 0; i < 7; ++i) imm.mode(i) = modes[i];
  imm.mix(nullptr, 3.0);
  EXPECT_LE((imm.predictedProbabilities() - (pi * pi * pi).transpose() * mu).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_LE((imm.lastTransition() - pi * pi * pi).cwiseAbs().maxCoeff(), 1e-15);
  for (int i = 0; i < 7; ++i)
  {
    EXPECT_LE((imm.mode(i).x - ref[i].x).cwiseAbs().maxCoeff(), 1e-12 * ref[i].x.cwiseAbs().maxCoeff()) << i;
    EXPECT_LE((imm.mode(i).P - ref[i].P).cwiseAbs().maxCoeff(), 1e-12 * ref[i].P.cwiseAbs().maxCoeff()) << i;
  }
  // One step is pi itself, bitwise.
  CIMMEstimator one(pi, mu, 0.0);
  for (int i = 0; i < 7; ++i) one.mode(i) = modes[i];
  one.mix(nullptr, 1.0);
  EXPECT_TRUE(one.lastTransition() == pi);
  EXPECT_TRUE(one.predictedProbabilities() == VecX(pi.transpose() * mu));
}

// ---------------------------------------------------------------------------------------------
// Known answers with an asymmetric Markov matrix (issue 30): the numbers below are worked out by
// hand from the textbook formulas (Bar-Shalom, Li & Kirubarajan, ch. 11; IMM paper Fig. 2, eq. 7)
//   c_j = sum_i p_ij mu_i,   mu_{i|j} = p_ij mu_i / c_j,   xbar_j = sum_i mu_{i|j} x_i,
//   Pbar_j = sum_i mu_{i|j} (P_i + (x_i - xbar_j)^2),        mu_j+ = c_j L_j / sum_l c_l L_l,
// with p_ij = P(mode j now | mode i before) (row i sums to 1). The matrix is far from symmetric,
// so using it transposed (p_ji for p_ij) gives other numbers, and the class's own mixingWeights()
// is never the reference.
// ---------------------------------------------------------------------------------------------

namespace
{
/** The asymmetric 3-mode example: p (rows sum to 1; p_20 = 0), mu, scalar means and variances. */
struct TAsymmetricExample
{
  MatX p = (MatX(3, 3) << 0.80, 0.15, 0.05,  //
            0.30, 0.60, 0.10,                 //
            0.00, 0.25, 0.75)
               .finished();
  VecX mu = (VecX(3) << 0.5, 0.3, 0.2).finished();
  std::vector<double> x = {0.0, 1.0, 3.0};
  std::vector<double> P = {1.0, 2.0, 0.5};
  // By hand: c_0 = 0.8*0.5 + 0.3*0.3 + 0*0.2 = 0.49; c_1 = 0.15*0.5 + 0.6*0.3 + 0.25*0.2 = 0.305;
  // c_2 = 0.05*0.5 + 0.1*0.3 + 0.75*0.2 = 0.205 (sum 1). With p transposed: 0.455, 0.35, 0.195.
  VecX c = (VecX(3) << 0.49, 0.305, 0.205).finished();
  // W(i, j) = mu_{i|j} = p_ij mu_i / c_j.
  MatX W = (MatX(3, 3) << 0.40 / 0.49, 0.075 / 0.305, 0.025 / 0.205,  //
            0.09 / 0.49, 0.18 / 0.305, 0.03 / 0.205,                   //
            0.00 / 0.49, 0.05 / 0.305, 0.15 / 0.205)
               .finished();

  std::unique_ptr<CIMMEstimator> make() const
  {
    auto imm = std::make_unique<CIMMEstimator>(p, mu, 0.0);
    for (int i = 0; i < 3; ++i) imm->mode(i) = TGaussian{VecX::Constant(1, x[i]), MatX::Constant(1, 1, P[i])};
    return imm;
  }
};
}  // namespace

TEST(IMM, AsymmetricMarkovMatrixMixingByHand)
{
  const TAsymmetricExample ex;
  // The hand-written weights are the formula's (guards against a typo above).
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) ASSERT_NEAR(ex.W(i, j), ex.p(i, j) * ex.mu[i] / ex.c[j], 1e-15);
  ASSERT_NEAR(ex.c.sum(), 1.0, 1e-15);
  const auto owner = ex.make();
  CIMMEstimator& imm = *owner;
  imm.mix();
  // Predicted probabilities c_j (eq. 7).
  EXPECT_NEAR(imm.predictedProbabilities()[0], 0.49, 1e-15);
  EXPECT_NEAR(imm.predictedProbabilities()[1], 0.305, 1e-15);
  EXPECT_NEAR(imm.predictedProbabilities()[2], 0.205, 1e-15);
  EXPECT_LT((imm.mixingWeights() - ex.W).cwiseAbs().maxCoeff(), 1e-15);
  // Mixed means and variances, e.g. xbar_0 = 0.09 / 0.49 * 1 = 0.18367..., worked out per mode.
  for (int j = 0; j < 3; ++j)
  {
    double xbar = 0;
    for (int i = 0; i < 3; ++i) xbar += ex.W(i, j) * ex.x[i];
    double Pbar = 0;
    for (int i = 0; i < 3; ++i) Pbar += ex.W(i, j) * (ex.P[i] + (ex.x[i] - xbar) * (ex.x[i] - xbar));
    EXPECT_NEAR(imm.mode(j).x[0], xbar, 1e-14) << "mode " << j;
    EXPECT_NEAR(imm.mode(j).P(0, 0), Pbar, 1e-14) << "mode " << j;
  }
  EXPECT_NEAR(imm.mode(0).x[0], 0.09 / 0.49, 1e-14);
  EXPECT_NEAR(imm.mode(2).x[0], (0.03 * 1.0 + 0.15 * 3.0) / 0.205, 1e-14);
  // Posterior with likelihoods L = (0.2, 0.5, 0.1): c .* L = (0.098, 0.1525, 0.0205), sum 0.271.
  imm.updateProbabilities((VecX(3) << std::log(0.2), std::log(0.5), std::log(0.1)).finished());
  EXPECT_NEAR(imm.probabilities()[0], 0.098 / 0.271, 1e-14);
  EXPECT_NEAR(imm.probabilities()[1], 0.1525 / 0.271, 1e-14);
  EXPECT_NEAR(imm.probabilities()[2], 0.0205 / 0.271, 1e-14);
}

TEST(IMM, AsymmetricMarkovMatrixOverTwoStepsByHand)
{
  // Two mixings without evidence (equal likelihoods): mu_2 = (p^T)^2 mu_0 written out.
  // Step 1: c = (0.49, 0.305, 0.205). Step 2: c'_0 = 0.8*0.49 + 0.3*0.305 = 0.4835,
  // c'_1 = 0.15*0.49 + 0.6*0.305 + 0.25*0.205 = 0.30775, c'_2 = 0.05*0.49 + 0.1*0.305 + 0.75*0.205 = 0.20875.
  const TAsymmetricExample ex;
  const auto owner = ex.make();
  CIMMEstimator& imm = *owner;
  imm.mix();
  imm.updateProbabilities(VecX::Zero(3));
  EXPECT_NEAR(imm.probabilities()[0], 0.49, 1e-15);
  imm.mix();
  EXPECT_NEAR(imm.predictedProbabilities()[0], 0.4835, 1e-15);
  EXPECT_NEAR(imm.predictedProbabilities()[1], 0.30775, 1e-15);
  EXPECT_NEAR(imm.predictedProbabilities()[2], 0.20875, 1e-15);
}

TEST(IMM, ProbabilityFloorKnownAnswer)
{
  // Floor f = 1e-3, 2 modes, p = [0.9 0.1; 0.2 0.8], mu = (0.5, 0.5): c = (0.55, 0.45). Log-likelihoods
  // (0, -50): the unfloored posterior of mode 1 is 0.45 e^-50 / 0.55 ~ 1.6e-22; floored and
  // renormalized: (1 - f, f) (the floor's mass taken from the mode above it). The next prediction then
  // starts from the floor: c'_1 = 0.1 (1 - f) + 0.8 f = 0.1007 (0.0999... without the floor).
  MatX p(2, 2);
  p << 0.9, 0.1, 0.2, 0.8;
  const double f = 1e-3;
  CIMMEstimator imm(p, VecX::Constant(2, 0.5), f);
  imm.setAllModes(VecX::Zero(1), MatX::Identity(1, 1));
  imm.mix();
  EXPECT_NEAR(imm.predictedProbabilities()[1], 0.45, 1e-15);
  imm.updateProbabilities(Eigen::Vector2d(0.0, -50.0));
  EXPECT_NEAR(imm.probabilities()[1], f, 1e-15);
  EXPECT_NEAR(imm.probabilities()[0], 1 - f, 1e-15);
  imm.mix();
  EXPECT_NEAR(imm.predictedProbabilities()[1], 0.1 * (1 - f) + 0.8 * f, 1e-15);
  // Three modes, two hopeless: (1 - 2f, f, f).
  MatX p3 = MatX::Constant(3, 3, 0.05);
  p3.diagonal().setConstant(0.9);
  CIMMEstimator imm3(p3, VecX::Constant(3, 1.0 / 3), f);
  imm3.setAllModes(VecX::Zero(1), MatX::Identity(1, 1));
  imm3.mix();
  imm3.updateProbabilities(Eigen::Vector3d(0.0, -60.0, -80.0));
  EXPECT_NEAR(imm3.probabilities()[0], 1 - 2 * f, 1e-15);
  EXPECT_NEAR(imm3.probabilities()[1], f, 1e-15);
  EXPECT_NEAR(imm3.probabilities()[2], f, 1e-15);
  // The rule for the modes above the floor (CIMMEstimator::updateProbabilities): they keep their
  // excess over f in proportion, scaled so that the sum is 1: mu_i = f + (a_i - f) (1 - r f) /
  // sum_{a_l >= f} (a_l - f), a the unfloored posterior. L = (1, 1, e^-60) after the step above:
  // c_0 = 0.9 (1 - 2f) + 0.05 * 2f, c_1 = 0.05 (1 - 2f) + 0.9 f + 0.05 f, a_{0,1} = c_{0,1} / (c_0 + c_1).
  imm3.mix();
  imm3.updateProbabilities(Eigen::Vector3d(0.0, 0.0, -60.0));
  const double c0 = 0.9 * (1 - 2 * f) + 0.1 * f, c1 = 0.05 * (1 - 2 * f) + 0.95 * f;
  const double a0 = c0 / (c0 + c1), a1 = c1 / (c0 + c1);
  EXPECT_NEAR(imm3.probabilities()[2], f, 1e-15);
  EXPECT_NEAR(imm3.probabilities()[0], f + (a0 - f) * (1 - 3 * f) / (a0 + a1 - 2 * f), 1e-14);
  EXPECT_NEAR(imm3.probabilities()[1], f + (a1 - f) * (1 - 3 * f) / (a0 + a1 - 2 * f), 1e-14);
}
