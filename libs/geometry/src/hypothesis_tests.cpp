/* imm-monoslam — hypothesis tests of eqs. (13)-(14). */
#include <immslam/geometry/construction_matrices.h>
#include <immslam/geometry/hypothesis_tests.h>
#include <immslam/geometry/join_meet.h>
#include <immslam/geometry/spherical_normalization.h>
#include <immslam/math/chi2.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>
#include <string>

namespace immslam::geometry
{
namespace
{
/** A spherically normalized input: value, covariance and d(value)/d(input). */
template <int N>
struct TNormalized
{
  Eigen::Matrix<double, N, 1> v;
  Eigen::Matrix<double, N, N> cov;
  Eigen::Matrix<double, N, N> J;
};

TNormalized<4> normalize4(const Vec4& x, const Mat4& cov)
{
  TNormalized<4> out;
  out.v = sphericallyNormalized<4>(x, &out.J);
  out.cov = out.J * cov * out.J.transpose();
  return out;
}

TNormalized<6> normalizeLine(const Vec6& L, const Mat6& cov)
{
  // Same as TUncertainLine3::normalized(), keeping the Jacobian for cross-covariances.
  TNormalized<6> out;
  Mat6 J;
  out.v = sphericallyNormalized<6>(L, &J);
  const Vec6 dl = dualLine(out.v).normalized();
  out.J = (Mat6::Identity() - dl * dl.transpose()) * J;
  out.cov = out.J * cov * out.J.transpose();
  return out;
}

template <int Nd, int Nx, int Ny>
THypothesisTest bilinearTest(const Eigen::Matrix<double, Nd, 1>& d,
                             const Eigen::Matrix<double, Nd, Nx>& J_d_x,
                             const Eigen::Matrix<double, Nd, Ny>& J_d_y, const TNormalized<Nx>& x,
                             const TNormalized<Ny>& y, const Eigen::Matrix<double, Nx, Ny>* cov_xy,
                             int dof, double alpha)
{
  Eigen::Matrix<double, Nx, Ny> cxy;
  if (cov_xy) cxy = x.J * (*cov_xy) * y.J.transpose();
  const Eigen::Matrix<double, Nd, Nd> S =
      propagateBilinear<Nd, Nx, Ny>(J_d_x, J_d_y, x.cov, y.cov, cov_xy ? &cxy : nullptr);
  return testRelation(d, S, dof, alpha);
}
}  // namespace

MatX dominantEigenvectors(const MatX& cov, int r, VecX* eigenvalues)
{
  if (cov.rows() != cov.cols() || r < 1 || r > cov.rows())
    throw std::invalid_argument("immslam/geometry/hypothesis_tests.cpp: dominantEigenvectors needs a "
                                "square matrix and 1 <= r <= its size (got r = " +
                                std::to_string(r) + ", " + std::to_string(cov.rows()) + "x" +
                                std::to_string(cov.cols()) + ")");
  const MatX S = 0.5 * (cov + cov.transpose());
  const Eigen::SelfAdjointEigenSolver<MatX> es(S);
  // Eigenvalues come in increasing order: the last r are the largest.
  const Eigen::Index n = S.rows();
  MatX U(n, r);
  if (eigenvalues) eigenvalues->resize(r);
  for (int i = 0; i < r; ++i)
  {
    U.col(i) = es.eigenvectors().col(n - 1 - i);
    if (eigenvalues) (*eigenvalues)[i] = es.eigenvalues()[n - 1 - i];
  }
  return U;
}

namespace
{
void requireLevel(double alpha, const char* what)
{
  if (!(alpha > 0 && alpha < 1))
    throw std::invalid_argument(std::string("immslam/geometry/hypothesis_tests.cpp: ") + what + " needs 0 < alpha < 1");
}

/** testRelation() against a given critical value. */
THypothesisTest testAgainst(const VecX& d, const MatX& cov_dd, int dof, double threshold)
{
  if (cov_dd.rows() != d.size() || cov_dd.cols() != d.size() || dof < 1 || dof > d.size())
    throw std::invalid_argument(
        "immslam/geometry/hypothesis_tests.cpp: testRelation needs a covariance of the size of d "
        "and 1 <= dof <= rows of d (got " +
        std::to_string(d.size()) + " rows, dof " + std::to_string(dof) + ")");
  THypothesisTest out;
  out.dof = dof;
  out.threshold = threshold;
  if (!d.allFinite() || !cov_dd.allFinite()) return out;
  VecX lambda;
  const MatX U = dominantEigenvectors(cov_dd, dof, &lambda);
  // The kept eigenvalues must be clearly positive, relative to the largest one.
  if (!(lambda[0] > 0) || !(lambda[dof - 1] > 1e-14 * lambda[0])) return out;
  const VecX z = U.transpose() * d;
  out.T = (z.array().square() / lambda.array()).sum();
  out.valid = std::isfinite(out.T);
  out.accepted = out.valid && out.T < out.threshold;
  return out;
}
}  // namespace

TSignificance TSignificance::At(double alpha)
{
  requireLevel(alpha, "TSignificance");
  TSignificance s;
  s.alpha = alpha;
  for (int r = 1; r <= 4; ++r) s.chi2[r] = math::chi2Quantile(1.0 - alpha, r);
  return s;
}

double TSignificance::threshold(int dof) const
{
  return dof >= 1 && dof <= 4 ? chi2[dof] : math::chi2Quantile(1.0 - alpha, dof);
}

THypothesisTest testRelation(const VecX& d, const MatX& cov_dd, int dof, double alpha)
{
  requireLevel(alpha, "testRelation");
  return testAgainst(d, cov_dd, dof, dof >= 1 ? math::chi2Quantile(1.0 - alpha, dof) : 0.0);
}

THypothesisTest testRelation(const VecX& d, const MatX& cov_dd, int dof, const TSignificance& level)
{
  requireLevel(level.alpha, "testRelation");
  return testAgainst(d, cov_dd, dof, dof >= 1 ? level.threshold(dof) : 0.0);
}

THypothesisTest testPointOnPlane(const TUncertainPoint3& X, const TUncertainPlane3& A, double alpha,
                                 const Mat4* cov_XA)
{
  const auto x = normalize4(X.X, X.cov);
  const auto a = normalize4(A.A, A.cov);
  const Eigen::Matrix<double, 1, 1> d(a.v.dot(x.v));
  const Mat14 J_d_x = a.v.transpose(), J_d_a = x.v.transpose();
  return bilinearTest<1, 4, 4>(d, J_d_x, J_d_a, x, a, cov_XA, 1, alpha);
}

THypothesisTest testPointOnLine(const TUncertainPoint3& X, const TUncertainLine3& L, double alpha,
                                const Mat46* cov_XL)
{
  const auto x = normalize4(X.X, X.cov);
  const auto l = normalizeLine(L.L, L.cov);
  Mat4 J_d_x;
  Mat46 J_d_l;
  const Vec4 d = joinPointLine(x.v, l.v, &J_d_x, &J_d_l);
  return bilinearTest<4, 4, 6>(d, J_d_x, J_d_l, x, l, cov_XL, 2, alpha);
}

THypothesisTest testLineOnPlane(const TUncertainLine3& L, const TUncertainPlane3& A, double alpha,
                                const Mat64* cov_LA)
{
  const auto l = normalizeLine(L.L, L.cov);
  const auto a = normalize4(A.A, A.cov);
  Mat46 J_d_l;
  Mat4 J_d_a;
  const Vec4 d = meetLinePlane(l.v, a.v, &J_d_l, &J_d_a);
  return bilinearTest<4, 6, 4>(d, J_d_l, J_d_a, l, a, cov_LA, 2, alpha);
}

THypothesisTest testLinesCoplanar(const TUncertainLine3& L, const TUncertainLine3& M, double alpha,
                                  const Mat6* cov_LM)
{
  const auto l = normalizeLine(L.L, L.cov);
  const auto m = normalizeLine(M.L, M.cov);
  const Vec6 Dl = dualLine(l.v), Dm = dualLine(m.v);
  const Eigen::Matrix<double, 1, 1> d(l.v.dot(Dm));
  const Mat16 J_d_l = Dm.transpose(), J_d_m = Dl.transpose();
  return bilinearTest<1, 6, 6>(d, J_d_l, J_d_m, l, m, cov_LM, 1, alpha);
}

THypothesisTest testIdenticalPoints(const TUncertainPoint3& X, const TUncertainPoint3& Y, double alpha,
                                    const Mat4* cov_XY)
{
  const auto x = normalize4(X.X, X.cov);
  const auto y = normalize4(Y.X, Y.cov);
  Mat64 J_d_x, J_d_y;
  const Vec6 d = joinPoints(x.v, y.v, &J_d_x, &J_d_y);
  return bilinearTest<6, 4, 4>(d, J_d_x, J_d_y, x, y, cov_XY, 3, alpha);
}

THypothesisTest testIdenticalPlanes(const TUncertainPlane3& A, const TUncertainPlane3& B, double alpha,
                                    const Mat4* cov_AB)
{
  const auto a = normalize4(A.A, A.cov);
  const auto b = normalize4(B.A, B.cov);
  Mat64 J_d_a, J_d_b;
  const Vec6 d = meetPlanes(a.v, b.v, &J_d_a, &J_d_b);
  return bilinearTest<6, 4, 4>(d, J_d_a, J_d_b, a, b, cov_AB, 3, alpha);
}

VecX identicalLinesDistance(const Vec6& L, const Vec6& M, MatX* J_d_L, MatX* J_d_M)
{
  const Mat4 OL = matO(L), ObM = matOBar(M);
  const Mat4 P = OL * ObM;
  VecX d = Eigen::Map<const VecX>(P.data(), 16);
  if (J_d_L) J_d_L->resize(16, 6);
  if (J_d_M) J_d_M->resize(16, 6);
  for (int j = 0; j < 4; ++j)
  {
    // Column j of O(L) OBar(M) is O(L) c_j with the point c_j = OBar(M) e_j:
    // d/dL = -PiBar(c_j)^T (join of a point and a line); d/dM = O(L) (-Pi(e_j)^T) (meet with e_j).
    if (J_d_L) J_d_L->middleRows<4>(4 * j) = -matPiBar(ObM.col(j)).transpose();
    if (J_d_M) J_d_M->middleRows<4>(4 * j) = -OL * matPi(Vec4::Unit(j)).transpose();
  }
  return d;
}

THypothesisTest testIdenticalLines(const TUncertainLine3& L, const TUncertainLine3& M, double alpha,
                                   const Mat6* cov_LM)
{
  const auto l = normalizeLine(L.L, L.cov);
  const auto m = normalizeLine(M.L, M.cov);
  MatX Jl, Jm;
  const Eigen::Matrix<double, 16, 1> d = identicalLinesDistance(l.v, m.v, &Jl, &Jm);
  const Eigen::Matrix<double, 16, 6> J_d_l = Jl, J_d_m = Jm;
  return bilinearTest<16, 6, 6>(d, J_d_l, J_d_m, l, m, cov_LM, 4, alpha);
}
}  // namespace immslam::geometry
