/* Tests: construction matrices vs numerical Jacobians, Euclidean consistency of joins/meets,
 * covariance propagation vs Monte Carlo, and the type-I / type-II error rates of the hypothesis tests
 * (shadow-filter paper eqs. (6)-(14)). */
#include <gtest/gtest.h>
#include <immslam/geometry/construction_matrices.h>
#include <immslam/geometry/hypothesis_tests.h>
#include <immslam/geometry/join_meet.h>
#include <immslam/geometry/ray_incidence.h>
#include <immslam/geometry/spherical_normalization.h>
#include <immslam/math/chi2.h>
#include <immslam/math/numerical_jacobian.h>
#include <immslam/math/quaternion.h>

#include "geometry_test_utils.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <functional>
#include <iostream>
#include <random>

using namespace immslam;
using namespace immslam::geometry;
using namespace immslam::geometry::test;

// ---------------------------------------------------------------------------------------------
// 1. Construction matrices and Jacobians
// ---------------------------------------------------------------------------------------------

TEST(ConstructionMatrices, MatchThePrintedEquations)
{
  // eq. (7) with X = (X1, Y1, Z1, W1) = (2, 3, 5, 7), eq. (9) with L = (1..6), entry by entry.
  const double X1 = 2, Y1 = 3, Z1 = 5, W1 = 7;
  Mat64 Pi7;
  Pi7 << W1, 0, 0, -X1, 0, W1, 0, -Y1, 0, 0, W1, -Z1, 0, -Z1, Y1, 0, Z1, 0, -X1, 0, -Y1, X1, 0, 0;
  EXPECT_EQ(matPi(Vec4(X1, Y1, Z1, W1)), Pi7);
  Vec6 L;
  L << 1, 2, 3, 4, 5, 6;
  Mat4 O9;
  O9 << 0, L[2], -L[1], -L[3], -L[2], 0, L[0], -L[4], L[1], -L[0], 0, -L[5], L[3], L[4], L[5], 0;
  EXPECT_EQ(matO(L), O9);
  // Duals.
  EXPECT_EQ(matPiBar(Vec4(1, 2, 3, 4)), matDual() * matPi(Vec4(1, 2, 3, 4)));
  EXPECT_EQ(matOBar(L), matO(matDual() * L));
  EXPECT_EQ(dualLine(L), matDual() * L);
}

TEST(ConstructionMatrices, PlueckerConvention)
{
  // L = X ^ Y for Euclidean points: (y - x, x cross y); first three = W1 Y0 - W2 X0.
  Rng rng(11);
  for (int t = 0; t < 20; ++t)
  {
    const Vec4 X = randomPoint(rng), Y = randomPoint(rng);
    const Vec6 L = joinPoints(X, Y);
    EXPECT_LT((L.head<3>() - (X[3] * Y.head<3>() - Y[3] * X.head<3>())).norm(), 1e-12);
    EXPECT_LT((L.tail<3>() - X.head<3>().cross(Y.head<3>())).norm(), 1e-12);
    EXPECT_NEAR(L.head<3>().dot(L.tail<3>()), 0.0, 1e-10);  // Plücker constraint
    EXPECT_LT((joinPoints(Y, X) + L).norm(), 1e-12);        // antisymmetry
  }
}

TEST(ConstructionMatrices, BilinearJacobiansMatchNumerical)
{
  Rng rng(1);
  const double tol = 1e-7;
  for (int t = 0; t < 30; ++t)
  {
    const Vec4 X = randomPoint(rng), Y = randomPoint(rng), A = randomPlane(rng), B = randomPlane(rng);
    const Vec6 L = randomLine(rng);
    {  // L = X ^ Y: U = Pi(X) = dL/dY, V = -Pi(Y) = dL/dX.
      Mat64 Jx, Jy;
      joinPoints(X, Y, &Jx, &Jy);
      VecX xy(8);
      xy << X, Y;
      const MatX Jn = math::numericalJacobian(
          [](const VecX& v) -> VecX { return joinPoints(v.head<4>(), v.tail<4>()); }, xy);
      EXPECT_LT((Jn.leftCols(4) - Jx).norm(), tol);
      EXPECT_LT((Jn.rightCols(4) - Jy).norm(), tol);
      EXPECT_LT((Jy - matPi(X)).norm(), 1e-15);
    }
    {  // A = X ^ L = O(L) X: dA/dX = O(L), dA/dL = -PiBar(X)^T.
      Mat4 Jx;
      Mat46 Jl;
      joinPointLine(X, L, &Jx, &Jl);
      VecX xl(10);
      xl << X, L;
      const MatX Jn = math::numericalJacobian(
          [](const VecX& v) -> VecX { return joinPointLine(v.head<4>(), v.tail<6>()); }, xl);
      EXPECT_LT((Jn.leftCols(4) - Jx).norm(), tol);
      EXPECT_LT((Jn.rightCols(6) - Jl).norm(), tol);
    }
    {  // L = A meet B = PiBar(A) B.
      Mat64 Ja, Jb;
      meetPlanes(A, B, &Ja, &Jb);
      VecX ab(8);
      ab << A, B;
      const MatX Jn = math::numericalJacobian(
          [](const VecX& v) -> VecX { return meetPlanes(v.head<4>(), v.tail<4>()); }, ab);
      EXPECT_LT((Jn.leftCols(4) - Ja).norm(), tol);
      EXPECT_LT((Jn.rightCols(4) - Jb).norm(), tol);
    }
    {  // X = L meet A = OBar(L) A.
      Mat46 Jl;
      Mat4 Ja;
      meetLinePlane(L, A, &Jl, &Ja);
      VecX la(10);
      la << L, A;
      const MatX Jn = math::numericalJacobian(
          [](const VecX& v) -> VecX { return meetLinePlane(v.head<6>(), v.tail<4>()); }, la);
      EXPECT_LT((Jn.leftCols(6) - Jl).norm(), tol);
      EXPECT_LT((Jn.rightCols(4) - Ja).norm(), tol);
    }
  }
}

TEST(ConstructionMatrices, CompositeJacobiansMatchNumerical)
{
  Rng rng(2);
  for (int t = 0; t < 30; ++t)
  {
    const Vec6 L = randomLine(rng), M = randomLine(rng), K = randomLine(rng);
    {
      Mat46 Jl, Jm;
      nearestPointOnLine(L, M, &Jl, &Jm);
      VecX lm(12);
      lm << L, M;
      const MatX Jn = math::numericalJacobian(
          [](const VecX& v) -> VecX { return nearestPointOnLine(v.head<6>(), v.tail<6>()); }, lm);
      EXPECT_LT((Jn.leftCols(6) - Jl).norm(), 1e-6 * (1 + Jl.norm()));
      EXPECT_LT((Jn.rightCols(6) - Jm).norm(), 1e-6 * (1 + Jm.norm()));
    }
    {
      Eigen::Matrix<double, 5, 6> Ji, Jj, Jk;
      const Vec3 aux = randomUnit(rng);
      const Eigen::Matrix<double, 5, 1> d = concurrencyDistance(L, M, K, aux, &Ji, &Jj, &Jk);
      // With v = Lh x Mh, Xij is nearestPointOnLine(M, L).
      const Vec4 X = nearestPointOnLine(M, L);
      EXPECT_LT((concurrencyDistance(L, M, K, L.head<3>().cross(M.head<3>())).tail<4>() - matO(K) * X).norm(),
                1e-10 * (1 + d.norm()));
      VecX lmk(18);
      lmk << L, M, K;
      const MatX Jn = math::numericalJacobian(
          [&aux](const VecX& v) -> VecX {
            return concurrencyDistance(v.segment<6>(0), v.segment<6>(6), v.segment<6>(12), aux);
          },
          lmk);
      EXPECT_LT((Jn.middleCols(0, 6) - Ji).norm(), 1e-6 * (1 + Ji.norm()));
      EXPECT_LT((Jn.middleCols(6, 6) - Jj).norm(), 1e-6 * (1 + Jj.norm()));
      EXPECT_LT((Jn.middleCols(12, 6) - Jk).norm(), 1e-6 * (1 + Jk.norm()));
    }
    {
      MatX Jl, Jm;
      identicalLinesDistance(L, M, &Jl, &Jm);
      VecX lm(12);
      lm << L, M;
      const MatX Jn = math::numericalJacobian(
          [](const VecX& v) -> VecX { return identicalLinesDistance(v.head<6>(), v.tail<6>()); }, lm);
      EXPECT_LT((Jn.leftCols(6) - Jl).norm(), 1e-7);
      EXPECT_LT((Jn.rightCols(6) - Jm).norm(), 1e-7);
    }
  }
}

TEST(UncertainEntities, NormalizationAndEuclideanJacobians)
{
  Rng rng(3);
  for (int t = 0; t < 20; ++t)
  {
    const Vec4 X = randomPoint(rng);
    Mat4 J4;
    sphericallyNormalized<4>(X, &J4);
    const MatX Jn4 = math::numericalJacobian(
        [](const VecX& v) -> VecX { return sphericallyNormalized<4>(Vec4(v)); }, VecX(X));
    EXPECT_LT((Jn4 - J4).norm(), 1e-8);
    const Vec6 L = randomLine(rng);
    Mat6 J6;
    sphericallyNormalized<6>(L, &J6);
    const MatX Jn6 = math::numericalJacobian(
        [](const VecX& v) -> VecX { return sphericallyNormalized<6>(Vec6(v)); }, VecX(L));
    EXPECT_LT((Jn6 - J6).norm(), 1e-8);

    const TUncertainPoint3 P(X, Mat4(randomCov(rng, 4, 0.01, 0.1)));
    Mat34 Jp;
    Mat3 covp;
    const Vec3 p = P.euclidean(&covp, &Jp);
    EXPECT_LT((p - X.head<3>() / X[3]).norm(), 1e-12);
    const MatX Jnp = math::numericalJacobian(
        [](const VecX& v) -> VecX { return TUncertainPoint3(Vec4(v)).euclidean(); }, VecX(X));
    EXPECT_LT((Jnp - Jp).norm(), 1e-7);
    EXPECT_LT((covp - Jp * P.cov * Jp.transpose()).norm(), 1e-12);
    // Normalized entities: unit norm, the vector itself in the covariance's null space.
    const TUncertainPoint3 Pn = P.normalized();
    EXPECT_NEAR(Pn.X.norm(), 1.0, 1e-12);
    EXPECT_LT((Pn.cov * Pn.X).norm(), 1e-12);
    // Euclidean coordinates and covariance are invariant under normalization.
    Mat3 covpn;
    EXPECT_LT((Pn.euclidean(&covpn) - p).norm(), 1e-12);
    EXPECT_LT((covpn - covp).norm(), 1e-10 * (1 + covp.norm()));
  }
  // Lines: the Plücker correction restores the constraint and moves the line little.
  for (int t = 0; t < 20; ++t)
  {
    const Vec6 L = randomLine(rng);
    const TUncertainLine3 bad(L + 1e-3 * L.norm() * Vec6(randn(rng, 6)), Mat6(randomCov(rng, 6, 0.01, 0.1)));
    EXPECT_GT(std::abs(bad.plueckerResidual()), 1e-7);
    const TUncertainLine3 good = bad.plueckerCorrected();
    EXPECT_NEAR(good.plueckerResidual(), 0.0, 1e-14);
    EXPECT_LT((good.L - bad.L.normalized()).norm(), 1e-2);
    // Normalized lines: unit norm, L and DL in the covariance's null space.
    EXPECT_NEAR(good.L.norm(), 1.0, 1e-12);
    EXPECT_LT((good.cov * good.L).norm(), 1e-12);
    EXPECT_LT((good.cov * dualLine(good.L)).norm(), 1e-12);
    const TUncertainLine3 byPD = TUncertainLine3::FromPointDirection(Vec3(1, 2, 3), Vec3(0, 0, 2));
    EXPECT_LT(byPD.distanceTo(Vec3(1, 2, -7)), 1e-12);
    EXPECT_NEAR(byPD.distanceTo(Vec3(4, 6, 0)), 5.0, 1e-12);
  }
  EXPECT_THROW(TUncertainPoint3::AtInfinity(Vec3(1, 0, 0)).euclidean(), std::runtime_error);
  EXPECT_THROW(TUncertainPoint3(Vec4::Zero()).normalized(), std::runtime_error);
}

// ---------------------------------------------------------------------------------------------
// 2. Joins and meets reproduce Euclidean geometry
// ---------------------------------------------------------------------------------------------

TEST(JoinMeet, ReproduceEuclideanGeometry)
{
  Rng rng(4);
  for (int t = 0; t < 50; ++t)
  {
    const Vec3 p = randn(rng, 3), q = randn(rng, 3), x = randn(rng, 3);
    const auto P = TUncertainPoint3::FromEuclidean(p), Q = TUncertainPoint3::FromEuclidean(q),
               X = TUncertainPoint3::FromEuclidean(x);
    // Line through p and q contains both, runs from p to q.
    const TUncertainLine3 L = join(P, Q);
    EXPECT_LT(L.distanceTo(p), 1e-12);
    EXPECT_LT(L.distanceTo(q), 1e-12);
    EXPECT_LT((L.direction() - (q - p)).norm(), 1e-12);
    EXPECT_LT((matO(L.L) * P.X).norm(), 1e-12);
    const Vec3 c = L.pointClosestToOrigin();
    EXPECT_LT(L.distanceTo(c), 1e-12);
    EXPECT_NEAR(c.dot(q - p), 0.0, 1e-12);
    // Plane through x and L contains x, p, q; its normal is along (q - p) x (x - p).
    const TUncertainPlane3 A = join(X, L);
    for (const Vec3& r : {p, q, x, Vec3(p + 2.5 * (q - p))}) EXPECT_NEAR(A.signedDistance(r), 0.0, 1e-12);
    EXPECT_LT(A.unitNormal().cross((q - p).cross(x - p).normalized()).norm(), 1e-10);
    // Meet of a line and a plane lies on both (compare with the parametric solution).
    const TUncertainPlane3 B = TUncertainPlane3::FromPointNormal(randn(rng, 3), randomUnit(rng));
    const TUncertainPoint3 Y = meet(L, B);
    const Vec3 y = Y.euclidean();
    EXPECT_NEAR(B.signedDistance(y), 0.0, 1e-9);
    EXPECT_LT(L.distanceTo(y), 1e-9);
    const double s = -(B.A.head<3>().dot(p) + B.A[3]) / B.A.head<3>().dot(q - p);
    EXPECT_LT((y - (p + s * (q - p))).norm(), 1e-9 * (1 + y.norm()));
    // Meet of two planes lies on both, direction along the normals' cross product.
    const TUncertainLine3 M = meet(A, B);
    const Vec3 m0 = M.pointClosestToOrigin();
    for (const Vec3& r : {m0, Vec3(m0 + M.direction())})
    {
      EXPECT_NEAR(A.signedDistance(r), 0.0, 1e-9);
      EXPECT_NEAR(B.signedDistance(r), 0.0, 1e-9);
    }
    EXPECT_LT(M.direction().cross(A.A.head<3>().cross(B.A.head<3>())).norm(), 1e-10);
    EXPECT_NEAR(M.plueckerResidual(), 0.0, 1e-12);
    // Nearest point of L to a skew line N: the closed-form common perpendicular.
    const Vec3 a = randn(rng, 3), u = randomUnit(rng);
    const TUncertainLine3 N = TUncertainLine3::FromPointDirection(a, u);
    const Vec3 w = (q - p).normalized(), r0 = p - a;
    const double b = w.dot(u), dd = w.dot(r0), e = u.dot(r0);
    const double sL = (b * e - dd) / (1 - b * b);
    const Vec3 foot = p + sL * w;
    const Vec3 z = TUncertainPoint3(nearestPointOnLine(L.L, N.L)).euclidean();
    EXPECT_LT((z - foot).norm(), 1e-8 * (1 + foot.norm()));
  }
}

// ---------------------------------------------------------------------------------------------
// 3. Covariance propagation vs Monte Carlo
// ---------------------------------------------------------------------------------------------

namespace
{
/** Relative Frobenius difference between the Monte Carlo covariance of the spherically normalized
 * output f(sample) and the propagated one (normalized likewise). */
template <int Nz>
double monteCarloMismatch(Rng& rng, const VecX& mean, const MatX& cov,
                          const std::function<Eigen::Matrix<double, Nz, 1>(const VecX&)>& f,
                          const Eigen::Matrix<double, Nz, 1>& z0, const Eigen::Matrix<double, Nz, Nz>& covz0,
                          int n = 20000)
{
  using VecZ = Eigen::Matrix<double, Nz, 1>;
  using MatZ = Eigen::Matrix<double, Nz, Nz>;
  MatZ Jn;
  const VecZ zs = sphericallyNormalized<Nz>(z0, &Jn);
  const MatZ prop = Jn * covz0 * Jn.transpose();
  const MatX B = covSqrt(cov);
  VecZ sum = VecZ::Zero();
  MatZ sum2 = MatZ::Zero();
  for (int i = 0; i < n; ++i)
  {
    VecZ z = sphericallyNormalized<Nz>(f(sample(rng, mean, B)));
    if (z.dot(zs) < 0) z = -z;
    sum += z;
    sum2 += z * z.transpose();
  }
  const VecZ m = sum / n;
  const MatZ S = (sum2 - n * m * m.transpose()) / (n - 1);
  return (S - prop).norm() / prop.norm();
}
}  // namespace

TEST(JoinMeet, CovarianceMatchesMonteCarlo)
{
  Rng rng(5);
  const double tol = 0.1;
  for (int withCross = 0; withCross < 2; ++withCross)
  {
    SCOPED_TRACE(withCross ? "correlated inputs (eq. 11)" : "independent inputs (eq. 12)");
    {  // point ^ point
      const Vec4 X = randomPoint(rng), Y = randomPoint(rng);
      MatX S = withCross ? randomCov(rng, 8, 0.005, 0.03) : MatX(MatX::Zero(8, 8));
      if (!withCross)
      {
        S.topLeftCorner(4, 4) = randomCov(rng, 4, 0.005, 0.03);
        S.bottomRightCorner(4, 4) = randomCov(rng, 4, 0.005, 0.03);
      }
      const Mat4 cXY = S.topRightCorner(4, 4);
      const TUncertainLine3 L = join(TUncertainPoint3(X, S.topLeftCorner(4, 4)),
                                     TUncertainPoint3(Y, S.bottomRightCorner(4, 4)), withCross ? &cXY : nullptr);
      VecX m(8);
      m << X, Y;
      const double e = monteCarloMismatch<6>(
          rng, m, S, [](const VecX& v) -> Vec6 { return joinPoints(v.head<4>(), v.tail<4>()); }, L.L, L.cov);
      std::cout << "[ mc       ] join of points: relative covariance mismatch " << e << "\n";
      EXPECT_LT(e, tol) << "join of points";
    }
    {  // point ^ line
      const Vec4 X = randomPoint(rng);
      const Vec6 L = randomLine(rng);
      MatX S = withCross ? randomCov(rng, 10, 0.005, 0.03) : MatX(MatX::Zero(10, 10));
      if (!withCross)
      {
        S.topLeftCorner(4, 4) = randomCov(rng, 4, 0.005, 0.03);
        S.bottomRightCorner(6, 6) = randomCov(rng, 6, 0.005, 0.03);
      }
      const Mat46 cXL = S.topRightCorner(4, 6);
      const TUncertainPlane3 A = join(TUncertainPoint3(X, S.topLeftCorner(4, 4)),
                                      TUncertainLine3(L, S.bottomRightCorner(6, 6)), withCross ? &cXL : nullptr);
      VecX m(10);
      m << X, L;
      const double e = monteCarloMismatch<4>(
          rng, m, S, [](const VecX& v) -> Vec4 { return joinPointLine(v.head<4>(), v.tail<6>()); }, A.A, A.cov);
      std::cout << "[ mc       ] join of point and line: relative covariance mismatch " << e << "\n";
      EXPECT_LT(e, tol) << "join of point and line";
    }
    {  // plane meet plane
      const Vec4 A = randomPlane(rng), B = randomPlane(rng);
      MatX S = withCross ? randomCov(rng, 8, 0.005, 0.03) : MatX(MatX::Zero(8, 8));
      if (!withCross)
      {
        S.topLeftCorner(4, 4) = randomCov(rng, 4, 0.005, 0.03);
        S.bottomRightCorner(4, 4) = randomCov(rng, 4, 0.005, 0.03);
      }
      const Mat4 cAB = S.topRightCorner(4, 4);
      const TUncertainLine3 L = meet(TUncertainPlane3(A, S.topLeftCorner(4, 4)),
                                     TUncertainPlane3(B, S.bottomRightCorner(4, 4)), withCross ? &cAB : nullptr);
      VecX m(8);
      m << A, B;
      const double e = monteCarloMismatch<6>(
          rng, m, S, [](const VecX& v) -> Vec6 { return meetPlanes(v.head<4>(), v.tail<4>()); }, L.L, L.cov);
      std::cout << "[ mc       ] meet of planes: relative covariance mismatch " << e << "\n";
      EXPECT_LT(e, tol) << "meet of planes";
    }
    {  // line meet plane
      const Vec6 L = randomLine(rng);
      const Vec4 A = randomPlane(rng);
      MatX S = withCross ? randomCov(rng, 10, 0.005, 0.03) : MatX(MatX::Zero(10, 10));
      if (!withCross)
      {
        S.topLeftCorner(6, 6) = randomCov(rng, 6, 0.005, 0.03);
        S.bottomRightCorner(4, 4) = randomCov(rng, 4, 0.005, 0.03);
      }
      const Mat64 cLA = S.topRightCorner(6, 4);
      const TUncertainPoint3 X = meet(TUncertainLine3(L, S.topLeftCorner(6, 6)),
                                      TUncertainPlane3(A, S.bottomRightCorner(4, 4)), withCross ? &cLA : nullptr);
      VecX m(10);
      m << L, A;
      const double e = monteCarloMismatch<4>(
          rng, m, S, [](const VecX& v) -> Vec4 { return meetLinePlane(v.head<6>(), v.tail<4>()); }, X.X, X.cov);
      std::cout << "[ mc       ] meet of line and plane: relative covariance mismatch " << e << "\n";
      EXPECT_LT(e, tol) << "meet of line and plane";
    }
  }
}

// ---------------------------------------------------------------------------------------------
// 4. Hypothesis tests: generic machinery, then type-I error rates under H0 and power under H1
// ---------------------------------------------------------------------------------------------

TEST(HypothesisTests, RankReducedStatistic)
{
  // d in the range of a rank-2 covariance embedded in 4 rows: T equals the 2-D Mahalanobis distance,
  // whatever the invertible recombination of the rows.
  Rng rng(7);
  const MatX B = randn(rng, 8).reshaped(4, 2);
  const Eigen::Vector2d z(0.3, -1.2);
  const MatX S2 = randomCov(rng, 2, 0.5, 2.0);
  const VecX d = B * z;
  const MatX S = B * S2 * B.transpose();
  const double Texpected = z.dot(S2.inverse() * z);
  const THypothesisTest r = testRelation(d, S, 2, 0.05);
  EXPECT_TRUE(r.valid);
  EXPECT_NEAR(r.T, Texpected, 1e-9 * Texpected);
  EXPECT_NEAR(r.threshold, math::chi2Quantile(0.95, 2), 1e-12);
  const MatX M = randomCov(rng, 4, 0.1, 3.0);  // any invertible recombination
  EXPECT_NEAR(testRelation(M * d, M * S * M.transpose(), 2, 0.05).T, Texpected, 1e-7 * Texpected);
  // Degenerate: no uncertainty -> invalid, neither accepted nor rejected.
  const THypothesisTest bad = testRelation(d, MatX::Zero(4, 4), 2, 0.05);
  EXPECT_FALSE(bad.valid);
  EXPECT_FALSE(bad.accepted);
  EXPECT_FALSE(bad.rejected());
  EXPECT_THROW(testRelation(d, S, 5, 0.05), std::invalid_argument);
  EXPECT_THROW(testRelation(d, S, 2, 1.5), std::invalid_argument);
}


TEST(HypothesisTests, PointOnLineErrorRates)
{
  Rng rng(8);
  const double alpha = 0.05;
  const int n = 10000;
  for (int h1 = 0; h1 < 2; ++h1)
  {
    int invalid = 0;
    const int rej = countRejections(
        n,
        [&]() {
          const Vec3 p = randn(rng, 3, 2.0), u = randomUnit(rng);
          const Vec3 q = p + uniform(rng, 0.5, 3.0) * u;
          Vec3 x = p + uniform(rng, -0.5, 1.5) * (q - p);
          const Mat3 Sp = randomCov(rng, 3, 0.005, 0.05), Sq = randomCov(rng, 3, 0.005, 0.05),
                     Sx = randomCov(rng, 3, 0.005, 0.05);
          if (h1) x += 0.6 * randomPerpendicular(rng, u);  // >= 10 sigma off the line
          const TUncertainLine3 L = join(noisyPoint(rng, p, Sp), noisyPoint(rng, q, Sq));
          return testPointOnLine(noisyPoint(rng, x, Sx), L, alpha);
        },
        &invalid);
    EXPECT_EQ(invalid, 0);
    reportRate(h1 ? "point-on-line, point moved 0.6 (>= 10 sigma) off the line" : "point-on-line under H0", rej, n);
    if (h1)
      EXPECT_GT(rej, 0.99 * n);
    else
      EXPECT_NEAR(static_cast<double>(rej) / n, alpha, 0.01);
  }
}

TEST(HypothesisTests, CoplanarLinesErrorRates)
{
  Rng rng(9);
  const double alpha = 0.05;
  const int n = 10000;
  for (int h1 = 0; h1 < 2; ++h1)
  {
    int invalid = 0;
    const int rej = countRejections(
        n,
        [&]() {
          const Vec3 x = randn(rng, 3, 2.0), u1 = randomUnit(rng);
          Vec3 u2 = randomUnit(rng);
          while (u1.cross(u2).norm() < 0.3) u2 = randomUnit(rng);
          const auto along = [&](const Vec3& u) {
            return Vec3(x + (uniform(rng, 0, 1) < 0.5 ? -1 : 1) * uniform(rng, 0.5, 2.0) * u);
          };
          Vec3 p1 = along(u1), q1 = along(u1), p2 = along(u2), q2 = along(u2);
          while ((q1 - p1).norm() < 0.5) q1 = along(u1);
          while ((q2 - p2).norm() < 0.5) q2 = along(u2);
          if (h1)
          {  // line 2 shifted along the common normal: skew lines 0.6 apart (>= 10 sigma)
            const Vec3 nrm = u1.cross(u2).normalized();
            p2 += 0.6 * nrm;
            q2 += 0.6 * nrm;
          }
          const auto cov = [&]() { return Mat3(randomCov(rng, 3, 0.005, 0.05)); };
          const TUncertainLine3 L1 = join(noisyPoint(rng, p1, cov()), noisyPoint(rng, q1, cov()));
          const TUncertainLine3 L2 = join(noisyPoint(rng, p2, cov()), noisyPoint(rng, q2, cov()));
          return testLinesCoplanar(L1, L2, alpha);
        },
        &invalid);
    EXPECT_EQ(invalid, 0);
    reportRate(h1 ? "coplanar lines, skew by 0.6 (>= 10 sigma)" : "coplanar lines under H0", rej, n);
    if (h1)
      EXPECT_GT(rej, 0.99 * n);
    else
      EXPECT_NEAR(static_cast<double>(rej) / n, alpha, 0.01);
  }
}

TEST(HypothesisTests, OtherRelationsUnderH0)
{
  // The remaining tests at 4000 trials each (binomial sd 0.34 %): rate within 5 % +- 1.5 %.
  Rng rng(10);
  const double alpha = 0.05;
  const int n = 4000;
  const auto cov = [&]() { return Mat3(randomCov(rng, 3, 0.005, 0.05)); };
  const auto planeFrom3 = [&](const Vec3& a, const Vec3& b, const Vec3& c) {
    return join(noisyPoint(rng, c, cov()), join(noisyPoint(rng, a, cov()), noisyPoint(rng, b, cov())));
  };
  const auto pointInPlane = [&](const Vec3& o, const Vec3& e1, const Vec3& e2) {
    return Vec3(o + uniform(rng, -2, 2) * e1 + uniform(rng, -2, 2) * e2);
  };
  struct TCase
  {
    const char* name;
    std::function<THypothesisTest()> trial;
  };
  const std::vector<TCase> cases = {
      {"point on plane",
       [&]() {
         const Vec3 o = randn(rng, 3), e1 = randomUnit(rng), e2 = randomPerpendicular(rng, e1);
         const TUncertainPlane3 A = planeFrom3(o + e1, o - e1 + e2, o - e2);
         return testPointOnPlane(noisyPoint(rng, pointInPlane(o, e1, e2), cov()), A, alpha);
       }},
      {"line in plane",
       [&]() {
         const Vec3 o = randn(rng, 3), e1 = randomUnit(rng), e2 = randomPerpendicular(rng, e1);
         const TUncertainPlane3 A = planeFrom3(o + e1, o - e1 + e2, o - e2);
         const Vec3 a = pointInPlane(o, e1, e2);
         Vec3 b = pointInPlane(o, e1, e2);
         while ((b - a).norm() < 0.5) b = pointInPlane(o, e1, e2);
         return testLineOnPlane(join(noisyPoint(rng, a, cov()), noisyPoint(rng, b, cov())), A, alpha);
       }},
      {"identical points",
       [&]() {
         const Vec3 x = randn(rng, 3, 2.0);
         return testIdenticalPoints(noisyPoint(rng, x, cov()), noisyPoint(rng, x, cov()), alpha);
       }},
      {"identical planes",
       [&]() {
         const Vec3 o = randn(rng, 3), e1 = randomUnit(rng), e2 = randomPerpendicular(rng, e1);
         const TUncertainPlane3 A = planeFrom3(o + e1, o - e1 + e2, o - e2);
         const TUncertainPlane3 B = planeFrom3(o + e2, o + e1 - e2, o - e1);
         return testIdenticalPlanes(A, B, alpha);
       }},
      {"identical lines",
       [&]() {
         const Vec3 p = randn(rng, 3), u = randomUnit(rng);
         const auto at = [&](double s) { return noisyPoint(rng, p + s * u, cov()); };
         return testIdenticalLines(join(at(-1.0), at(1.0)), join(at(-1.5), at(0.5)), alpha);
       }},
  };
  for (const TCase& c : cases)
  {
    int invalid = 0;
    const int rej = countRejections(n, c.trial, &invalid);
    reportRate(c.name, rej, n);
    EXPECT_EQ(invalid, 0) << c.name;
    EXPECT_NEAR(static_cast<double>(rej) / n, alpha, 0.015) << c.name;
  }
}

TEST(HypothesisTests, PointOnLineWithCrossCovariance)
{
  // X is observed as P + eta, where P is also one of the two points defining L: X and L are correlated,
  // cov_XL = cov_XP (dL/dP)^T = Sigma_P (-Pi(Q))^T. With it the test keeps its level.
  Rng rng(15);
  const double alpha = 0.05;
  const int n = 4000;
  int rejCross = 0, rejIndep = 0;
  for (int i = 0; i < n; ++i)
  {
    const Vec3 p = randn(rng, 3, 2.0), q = p + uniform(rng, 0.5, 3.0) * randomUnit(rng);
    const Mat3 Sp = randomCov(rng, 3, 0.01, 0.05), Sq = randomCov(rng, 3, 0.01, 0.05),
               Se = randomCov(rng, 3, 0.002, 0.01);
    const TUncertainPoint3 P = noisyPoint(rng, p, Sp), Q = noisyPoint(rng, q, Sq);
    const TUncertainPoint3 X =
        TUncertainPoint3::FromEuclidean(P.X.head<3>() + covSqrt(Se) * randn(rng, 3), Sp + Se);
    const TUncertainLine3 L = join(P, Q);
    Mat4 cXP = Mat4::Zero();
    cXP.topLeftCorner<3, 3>() = Sp;
    const Mat46 cXL = cXP * (-matPi(Q.X)).transpose();
    rejCross += testPointOnLine(X, L, alpha, &cXL).rejected();
    rejIndep += testPointOnLine(X, L, alpha).rejected();
  }
  reportRate("point-on-line, correlated point and line, with cov_XL", rejCross, n);
  reportRate("point-on-line, correlated point and line, ignoring it (info)", rejIndep, n);
  EXPECT_NEAR(static_cast<double>(rejCross) / n, alpha, 0.015);
}
