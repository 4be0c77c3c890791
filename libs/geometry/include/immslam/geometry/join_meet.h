/* imm-monoslam — joins and meets with first-order covariance propagation (shadow-filter paper,
 * eqs. (6)-(12)). */
#pragma once

#include <immslam/geometry/TUncertainLine3.h>
#include <immslam/geometry/TUncertainPlane3.h>
#include <immslam/geometry/TUncertainPoint3.h>
#include <immslam/geometry/geometry_types.h>

namespace immslam::geometry
{
/** First-order covariance of a function z(x, y) with Jacobians J_z_x = V(y), J_z_y = U(x)
 * (eq. (11); eq. (12) when cov_xy is null):
 * \f[ \Sigma_{zz} = V \Sigma_{xx} V^\top + U \Sigma_{yy} U^\top + V \Sigma_{xy} U^\top
 *     + U \Sigma_{xy}^\top V^\top. \f]
 * (The paper prints \f$ \Sigma_{xy} \f$ in both off-diagonal blocks of the joint covariance; the
 * lower one is its transpose \f$ \Sigma_{yx} = \Sigma_{xy}^\top \f$.)
 * \param cov_xy optional cross-covariance \f$ E[\delta x\, \delta y^\top] \f$ (Nx x Ny). */
template <int Nz, int Nx, int Ny>
Eigen::Matrix<double, Nz, Nz> propagateBilinear(const Eigen::Matrix<double, Nz, Nx>& J_z_x,
                                                const Eigen::Matrix<double, Nz, Ny>& J_z_y,
                                                const Eigen::Matrix<double, Nx, Nx>& cov_xx,
                                                const Eigen::Matrix<double, Ny, Ny>& cov_yy,
                                                const Eigen::Matrix<double, Nx, Ny>* cov_xy = nullptr)
{
  Eigen::Matrix<double, Nz, Nz> S =
      J_z_x * cov_xx * J_z_x.transpose() + J_z_y * cov_yy * J_z_y.transpose();
  if (cov_xy)
  {
    const Eigen::Matrix<double, Nz, Nz> C = J_z_x * (*cov_xy) * J_z_y.transpose();
    S += C + C.transpose();
  }
  return 0.5 * (S + S.transpose());
}

/** \name Exact bilinear constructions (values and Jacobians, the U and V of eq. (10))
 * @{ */

/** The line through two points, \f$ \mathbf L = \mathbf X \wedge \mathbf Y = \Pi(\mathbf X)\mathbf Y \f$
 * (eq. (6)); it runs from X to Y (see TUncertainLine3).
 * \param J_L_X optional \f$ -\Pi(\mathbf Y) \f$. \param J_L_Y optional \f$ \Pi(\mathbf X) \f$. */
Vec6 joinPoints(const Vec4& X, const Vec4& Y, Mat64* J_L_X = nullptr, Mat64* J_L_Y = nullptr);

/** The plane through the point X and the line L, \f$ \mathbf A = \mathbf X \wedge \mathbf L =
 * O(\mathbf L)\mathbf X \f$ (eq. (8)-(9)).
 * \param J_A_X optional \f$ O(\mathbf L) \f$. \param J_A_L optional \f$ -\bar\Pi(\mathbf X)^\top \f$. */
Vec4 joinPointLine(const Vec4& X, const Vec6& L, Mat4* J_A_X = nullptr, Mat46* J_A_L = nullptr);

/** The intersection line of two planes, \f$ \mathbf L = \mathbf A \cap \mathbf B =
 * \bar\Pi(\mathbf A)\mathbf B \f$ (direction \f$ \mathbf A_h \times \mathbf B_h \f$).
 * \param J_L_A optional \f$ -\bar\Pi(\mathbf B) \f$. \param J_L_B optional \f$ \bar\Pi(\mathbf A) \f$. */
Vec6 meetPlanes(const Vec4& A, const Vec4& B, Mat64* J_L_A = nullptr, Mat64* J_L_B = nullptr);

/** The intersection point of a line and a plane, \f$ \mathbf X = \mathbf L \cap \mathbf A =
 * \bar O(\mathbf L)\mathbf A \f$ (zero if L lies in A).
 * \param J_X_L optional \f$ -\Pi(\mathbf A)^\top \f$. \param J_X_A optional \f$ \bar O(\mathbf L) \f$. */
Vec4 meetLinePlane(const Vec6& L, const Vec4& A, Mat46* J_X_L = nullptr, Mat4* J_X_A = nullptr);
/** @} */

/** \name Uncertain constructions (eqs. (10)-(12))
 * Each returns the exact bilinear value and its first-order covariance; the inputs are used as
 * given (neither normalized nor conditioned) and so is the result: call normalized() on it to get
 * Heuel's spherically normalized form. With a cross-covariance the correlated form eq. (11) is used,
 * otherwise eq. (12) (independent inputs).
 * @{ */

/** Line X ^ Y (eq. (6)). \param cov_XY optional \f$ E[\delta X \delta Y^\top] \f$ (4x4), e.g. a camera
 * centre C and a far point C + s d on its viewing ray share the centre's uncertainty. */
TUncertainLine3 join(const TUncertainPoint3& X, const TUncertainPoint3& Y, const Mat4* cov_XY = nullptr);

/** Plane X ^ L (eq. (8)). \param cov_XL optional \f$ E[\delta X \delta L^\top] \f$ (4x6). */
TUncertainPlane3 join(const TUncertainPoint3& X, const TUncertainLine3& L, const Mat46* cov_XL = nullptr);

/** Line A meet B. \param cov_AB optional \f$ E[\delta A \delta B^\top] \f$ (4x4). */
TUncertainLine3 meet(const TUncertainPlane3& A, const TUncertainPlane3& B, const Mat4* cov_AB = nullptr);

/** Point L meet A. \param cov_LA optional \f$ E[\delta L \delta A^\top] \f$ (6x4). */
TUncertainPoint3 meet(const TUncertainLine3& L, const TUncertainPlane3& A, const Mat64* cov_LA = nullptr);
/** @} */
}  // namespace immslam::geometry
