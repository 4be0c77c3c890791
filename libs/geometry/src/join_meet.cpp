/* imm-monoslam — joins and meets (eqs. (6)-(12)); the matrices are derived in
 * construction_matrices.cpp. */
#include <immslam/geometry/construction_matrices.h>
#include <immslam/geometry/join_meet.h>

namespace immslam::geometry
{
Vec6 joinPoints(const Vec4& X, const Vec4& Y, Mat64* J_L_X, Mat64* J_L_Y)
{
  const Mat64 PiX = matPi(X);
  if (J_L_X) *J_L_X = -matPi(Y);  // X ^ Y = -(Y ^ X) = -Pi(Y) X
  if (J_L_Y) *J_L_Y = PiX;
  return PiX * Y;
}

Vec4 joinPointLine(const Vec4& X, const Vec6& L, Mat4* J_A_X, Mat46* J_A_L)
{
  const Mat4 O = matO(L);
  if (J_A_X) *J_A_X = O;
  if (J_A_L) *J_A_L = -matPiBar(X).transpose();
  return O * X;
}

Vec6 meetPlanes(const Vec4& A, const Vec4& B, Mat64* J_L_A, Mat64* J_L_B)
{
  const Mat64 PbA = matPiBar(A);
  if (J_L_A) *J_L_A = -matPiBar(B);  // antisymmetric like the join of points
  if (J_L_B) *J_L_B = PbA;
  return PbA * B;
}

Vec4 meetLinePlane(const Vec6& L, const Vec4& A, Mat46* J_X_L, Mat4* J_X_A)
{
  const Mat4 Ob = matOBar(L);
  if (J_X_L) *J_X_L = -matPi(A).transpose();
  if (J_X_A) *J_X_A = Ob;
  return Ob * A;
}

TUncertainLine3 join(const TUncertainPoint3& X, const TUncertainPoint3& Y, const Mat4* cov_XY)
{
  Mat64 V, U;
  const Vec6 L = joinPoints(X.X, Y.X, &V, &U);
  return TUncertainLine3(L, propagateBilinear<6, 4, 4>(V, U, X.cov, Y.cov, cov_XY));
}

TUncertainPlane3 join(const TUncertainPoint3& X, const TUncertainLine3& L, const Mat46* cov_XL)
{
  Mat4 J_X;
  Mat46 J_L;
  const Vec4 A = joinPointLine(X.X, L.L, &J_X, &J_L);
  return TUncertainPlane3(A, propagateBilinear<4, 4, 6>(J_X, J_L, X.cov, L.cov, cov_XL));
}

TUncertainLine3 meet(const TUncertainPlane3& A, const TUncertainPlane3& B, const Mat4* cov_AB)
{
  Mat64 V, U;
  const Vec6 L = meetPlanes(A.A, B.A, &V, &U);
  return TUncertainLine3(L, propagateBilinear<6, 4, 4>(V, U, A.cov, B.cov, cov_AB));
}

TUncertainPoint3 meet(const TUncertainLine3& L, const TUncertainPlane3& A, const Mat64* cov_LA)
{
  Mat46 J_L;
  Mat4 J_A;
  const Vec4 X = meetLinePlane(L.L, A.A, &J_L, &J_A);
  return TUncertainPoint3(X, propagateBilinear<4, 6, 4>(J_L, J_A, L.cov, A.cov, cov_LA));
}
}  // namespace immslam::geometry
