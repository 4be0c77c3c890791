/* imm-monoslam — concurrency of three uncertain viewing rays (classifier core). */
#include <immslam/geometry/construction_matrices.h>
#include <immslam/geometry/join_meet.h>
#include <immslam/geometry/ray_incidence.h>
#include <immslam/geometry/spherical_normalization.h>
#include <immslam/math/quaternion.h>

#include <stdexcept>

namespace immslam::geometry
{
TUncertainLine3 viewingRay(const Vec3& centre, const Mat3& cov_centre, const Vec3& direction,
                           const Mat3& cov_direction, const Mat3* cov_centre_direction)
{
  const TUncertainPoint3 C = TUncertainPoint3::FromEuclidean(centre, cov_centre);
  const TUncertainPoint3 D = TUncertainPoint3::AtInfinity(direction, cov_direction);
  if (!cov_centre_direction) return join(C, D);
  Mat4 cCD = Mat4::Zero();
  cCD.topLeftCorner<3, 3>() = *cov_centre_direction;
  return join(C, D, &cCD);
}

Vec4 nearestPointOnLine(const Vec6& L, const Vec6& M, Mat46* J_X_L, Mat46* J_X_M)
{
  // N = (Mh x Lh, 0): the point at infinity of the common normal.
  Vec4 N;
  N << M.head<3>().cross(L.head<3>()), 0.0;
  // A = N ^ M = O(M) N: the plane through M containing the normal direction.
  Mat4 J_A_N;
  Mat46 J_A_M;
  const Vec4 A = joinPointLine(N, M, &J_A_N, &J_A_M);
  // X = L meet A = OBar(L) A.
  Mat46 J_X_Ldirect;
  Mat4 J_X_A;
  const Vec4 X = meetLinePlane(L, A, &J_X_Ldirect, &J_X_A);
  if (J_X_L || J_X_M)
  {
    // Chain rule: dN/dLh = [Mh]x, dN/dMh = -[Lh]x (only the first three rows of N vary).
    Mat46 J_N_L = Mat46::Zero(), J_N_M = Mat46::Zero();
    J_N_L.topLeftCorner<3, 3>() = math::skew(M.head<3>());
    J_N_M.topLeftCorner<3, 3>() = -math::skew(L.head<3>());
    if (J_X_L) *J_X_L = J_X_Ldirect + J_X_A * J_A_N * J_N_L;
    if (J_X_M) *J_X_M = J_X_A * (J_A_M + J_A_N * J_N_M);
  }
  return X;
}

Eigen::Matrix<double, 5, 1> concurrencyDistance(const Vec6& Li, const Vec6& Lj, const Vec6& Lk,
                                                const Vec3& v, Eigen::Matrix<double, 5, 6>* J_d_Li,
                                                Eigen::Matrix<double, 5, 6>* J_d_Lj,
                                                Eigen::Matrix<double, 5, 6>* J_d_Lk)
{
  Eigen::Matrix<double, 5, 1> d;
  // d1 = Li^T D Lj: coplanarity of rays i and j.
  d[0] = Li.dot(dualLine(Lj));
  // Xij = Lj meet (V ^ Li): the plane through ray i parallel to v, cut by ray j (v held fixed).
  Vec4 V;
  V << v, 0.0;
  Mat46 J_A_Li;
  const Vec4 A = joinPointLine(V, Li, nullptr, &J_A_Li);
  Mat46 J_X_Lj;
  Mat4 J_X_A;
  const Vec4 X = meetLinePlane(Lj, A, &J_X_Lj, &J_X_A);
  // d2 = O(Lk) Xij: the plane through ray k and Xij vanishes.
  Mat4 J_d2_X;
  Mat46 J_d2_Lk;
  d.tail<4>() = joinPointLine(X, Lk, &J_d2_X, &J_d2_Lk);
  if (J_d_Li)
  {
    J_d_Li->row(0) = dualLine(Lj).transpose();
    J_d_Li->bottomRows<4>() = J_d2_X * J_X_A * J_A_Li;  // chain rule: Li -> A -> Xij -> d2
  }
  if (J_d_Lj)
  {
    J_d_Lj->row(0) = dualLine(Li).transpose();
    J_d_Lj->bottomRows<4>() = J_d2_X * J_X_Lj;  // chain rule: Lj -> Xij -> d2
  }
  if (J_d_Lk)
  {
    J_d_Lk->row(0).setZero();
    J_d_Lk->bottomRows<4>() = J_d2_Lk;
  }
  return d;
}

namespace
{
/** The rays spherically normalized into l (with the Plücker tangent projection of
 * TUncertainLine3::normalized()) and their joint 18x18 covariance after it into S (`cov_rays`,
 * else the rays' own blocks). */
void normalizeRays(const TUncertainLine3* const rays[3], const MatX* cov_rays, Vec6 l[3], MatX& S)
{
  if (cov_rays)
    S = *cov_rays;
  else
  {
    S.setZero();
    for (int r = 0; r < 3; ++r) S.block<6, 6>(6 * r, 6 * r) = rays[r]->cov;
  }
  MatX Jn = MatX::Zero(18, 18);
  for (int r = 0; r < 3; ++r)
  {
    Mat6 J;
    l[r] = sphericallyNormalized<6>(rays[r]->L, &J);
    const Vec6 dl = dualLine(l[r]).normalized();
    Jn.block<6, 6>(6 * r, 6 * r) = (Mat6::Identity() - dl * dl.transpose()) * J;
  }
  S = Jn * S * Jn.transpose();
}

/** The pair with the widest angle between directions (it forms the intersection point) into
 * out.pair, the other ray into out.third. */
void widestPair(const Vec6 l[3], TRayIncidenceTest& out)
{
  double best = -1;
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
    {
      const double s = l[a].head<3>().cross(l[b].head<3>()).norm() /
                       (l[a].head<3>().norm() * l[b].head<3>().norm());
      if (s > best)
      {
        best = s;
        out.pair[0] = a;
        out.pair[1] = b;
        out.third = 3 - a - b;
      }
    }
}
}  // namespace

TRayIncidenceTest threeRaysMeet(const TUncertainLine3& ray1, const TUncertainLine3& ray2,
                                const TUncertainLine3& ray3, double alpha, const MatX* cov_rays)
{
  if (!(alpha > 0 && alpha < 1))
    throw std::invalid_argument("immslam/geometry/ray_incidence.cpp: threeRaysMeet needs 0 < alpha < 1");
  return threeRaysMeet(ray1, ray2, ray3, TSignificance::At(alpha), cov_rays);
}

TRayIncidenceTest threeRaysMeet(const TUncertainLine3& ray1, const TUncertainLine3& ray2,
                                const TUncertainLine3& ray3, const TSignificance& level, const MatX* cov_rays)
{
  if (cov_rays && (cov_rays->rows() != 18 || cov_rays->cols() != 18))
    throw std::invalid_argument(
        "immslam/geometry/ray_incidence.cpp: threeRaysMeet needs an 18x18 joint covariance of the rays");
  if (!(level.alpha > 0 && level.alpha < 1))
    throw std::invalid_argument("immslam/geometry/ray_incidence.cpp: threeRaysMeet needs 0 < alpha < 1");

  const TUncertainLine3* rays[3] = {&ray1, &ray2, &ray3};
  Vec6 l[3];
  MatX S(18, 18);
  normalizeRays(rays, cov_rays, l, S);
  TRayIncidenceTest out;
  widestPair(l, out);
  const int i = out.pair[0], j = out.pair[1], k = out.third;

  Eigen::Matrix<double, 5, 6> Ji, Jj, Jk;
  const Vec3 v = l[i].head<3>().cross(l[j].head<3>());
  const Eigen::Matrix<double, 5, 1> d = concurrencyDistance(l[i], l[j], l[k], v, &Ji, &Jj, &Jk);
  Eigen::Matrix<double, 5, 18> J;
  J.middleCols<6>(6 * i) = Ji;
  J.middleCols<6>(6 * j) = Jj;
  J.middleCols<6>(6 * k) = Jk;

  // Reduce d2 (4 rows, rank 2) to its two dominant combinations, then test the 3-vector jointly.
  const Eigen::Matrix<double, 4, 18> J2 = J.bottomRows<4>();
  const MatX U2 = dominantEigenvectors(J2 * S * J2.transpose(), 2);
  Eigen::Matrix<double, 3, 1> dr;
  dr << d[0], U2.transpose() * d.tail<4>();
  Eigen::Matrix<double, 3, 18> Jr;
  Jr << J.row(0), U2.transpose() * J2;
  MatX Sr = Jr * S * Jr.transpose();
  Sr = 0.5 * (Sr + Sr.transpose()).eval();

  out.test = testRelation(dr, Sr, 3, level);
  out.coplanar = testRelation(dr.head<1>(), Sr.topLeftCorner<1, 1>(), 1, level);
  out.onThirdRay = testRelation(dr.tail<2>(), Sr.bottomRightCorner<2, 2>(), 2, level);

  // The intersection point with its covariance (first order, from all the rays' covariance).
  Mat46 J_X_Lj, J_X_Li;
  const Vec4 X = nearestPointOnLine(l[j], l[i], &J_X_Lj, &J_X_Li);
  Eigen::Matrix<double, 4, 18> JX = Eigen::Matrix<double, 4, 18>::Zero();
  JX.middleCols<6>(6 * i) = J_X_Li;
  JX.middleCols<6>(6 * j) = J_X_Lj;
  if (X.allFinite() && X.norm() > 0)
    out.intersection = TUncertainPoint3(X, JX * S * JX.transpose()).normalized();
  else
    out.intersection = TUncertainPoint3(X, Mat4::Zero());
  return out;
}
}  // namespace immslam::geometry
