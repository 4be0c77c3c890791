/* imm-monoslam — construction matrices (shadow-filter paper eqs. (7), (9) and their duals).
 *
 * Derivations (points X = (x, w), planes A = (a, a0), lines L = (l, m) = (Lh, L0)):
 * - eq. (7): Pi(X) Y = (w y - v x, x cross y) for Y = (y, v): rows 1-3 are [w I, -x], rows 4-6 are
 *   [[x]x, 0] (row 4: -Z1 Y2 + Y1 Z2 = (x cross y)_1, ...). Antisymmetric: Pi(X) Y = -Pi(Y) X.
 * - eq. (9) as printed: O(L) X = (-[l]x x - w m, m.x) = (x cross l - w m, m.x). The plane contains X:
 *   (x cross l).x - w m.x + w m.x = 0; and every point p of L (m = p cross l):
 *   (x cross l).p - w m.p + m.x = -x.(p cross l) - 0 + m.x = 0 (w = 1, m.p = 0). As a function of L it is
 *   dA/dl = [x]x, dA/dm = [-w I; x^T], which is -(D Pi(X))^T = -PiBar(X)^T.
 * - meet of planes: join the planes as points, Pi(A) B = (a0 b - b0 a, a cross b), then dualize:
 *   the direction of the intersection is a cross b, and for p on both planes
 *   p cross (a cross b) = a (p.b) - b (p.a) = a0 b - b0 a, the moment. So PiBar(A) = D Pi(A).
 * - meet of line and plane: O(D L) A = (a cross m - a0 l, l.a). On A: a.(a cross m) - a0 a.l +
 *   a0 l.a = 0; on L: X0 cross l = (a cross m) cross l = m (l.a) - a (l.m) = Xh m (Plücker
 *   constraint l.m = 0). As a function of L: dX/dl = [-a0 I; a^T], dX/dm = [[a]x; 0] = -Pi(A)^T.
 */
#include <immslam/geometry/construction_matrices.h>
#include <immslam/math/quaternion.h>

namespace immslam::geometry
{
Mat64 matPi(const Vec4& X)
{
  Mat64 P;
  P.topLeftCorner<3, 3>() = X[3] * Mat3::Identity();
  P.topRightCorner<3, 1>() = -X.head<3>();
  P.bottomLeftCorner<3, 3>() = math::skew(X.head<3>());
  P.bottomRightCorner<3, 1>().setZero();
  return P;
}

Mat64 matPiBar(const Vec4& A)
{
  Mat64 P;
  P.topLeftCorner<3, 3>() = math::skew(A.head<3>());
  P.topRightCorner<3, 1>().setZero();
  P.bottomLeftCorner<3, 3>() = A[3] * Mat3::Identity();
  P.bottomRightCorner<3, 1>() = -A.head<3>();
  return P;
}

Mat6 matDual()
{
  Mat6 D = Mat6::Zero();
  D.topRightCorner<3, 3>().setIdentity();
  D.bottomLeftCorner<3, 3>().setIdentity();
  return D;
}

Vec6 dualLine(const Vec6& L)
{
  Vec6 out;
  out << L.tail<3>(), L.head<3>();
  return out;
}

Mat4 matO(const Vec6& L)
{
  Mat4 O;
  O.topLeftCorner<3, 3>() = -math::skew(L.head<3>());
  O.topRightCorner<3, 1>() = -L.tail<3>();
  O.bottomLeftCorner<1, 3>() = L.tail<3>().transpose();
  O(3, 3) = 0;
  return O;
}

Mat4 matOBar(const Vec6& L) { return matO(dualLine(L)); }
}  // namespace immslam::geometry
