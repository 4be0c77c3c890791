/* imm-monoslam — an uncertain 3D line in Plücker coordinates (shadow-filter paper, eqs. (6)-(9)). */
#pragma once

#include <immslam/geometry/geometry_types.h>

namespace immslam::geometry
{
/** An uncertain 3D line: Plücker 6-vector \f$ \mathbf L = (\mathbf L_h^\top, \mathbf L_0^\top)^\top \f$
 * with its 6x6 covariance.
 *
 * Convention (fixed by the paper's eq. (7), checked row by row): the join of the points
 * \f$ \mathbf X = (\mathbf X_0, X_h) \f$ and \f$ \mathbf Y = (\mathbf Y_0, Y_h) \f$ is
 * \f[ \mathbf L = \mathbf X \wedge \mathbf Y = \Pi(\mathbf X)\,\mathbf Y =
 *     \begin{pmatrix} X_h \mathbf Y_0 - Y_h \mathbf X_0 \\ \mathbf X_0 \times \mathbf Y_0 \end{pmatrix},
 * \f]
 * i.e. rows 1-3 of \f$ \Pi(\mathbf X) \f$ give \f$ W_1 (X_2,Y_2,Z_2) - W_2 (X_1,Y_1,Z_1) \f$ and rows
 * 4-6 give \f$ (Y_1 Z_2 - Z_1 Y_2,\; Z_1 X_2 - X_1 Z_2,\; X_1 Y_2 - Y_1 X_2) \f$. So:
 * - \f$ \mathbf L_h \f$ (first three) is the direction, pointing from X to Y (for Euclidean points
 *   \f$ \mathbf y - \mathbf x \f$);
 * - \f$ \mathbf L_0 \f$ (last three) is the moment, \f$ \mathbf L_0 = \mathbf p \times \mathbf L_h \f$
 *   for any point p of the line (no sign flip w.r.t. \f$ \mathbf X_0 \times \mathbf Y_0 \f$);
 * - the Plücker constraint is \f$ \mathbf L_h^\top \mathbf L_0 = \tfrac12 \mathbf L^\top D \mathbf L = 0
 *   \f$ with the dualization \f$ D = \begin{pmatrix} 0 & I_3 \\ I_3 & 0\end{pmatrix} \f$ (matDual()).
 *
 * A valid uncertain line has a covariance whose null space contains \f$ D\mathbf L \f$ (the first-order
 * consequence of the constraint); lines made by join() and meet() have it by construction. Opposite
 * vectors are the same (undirected) line.
 * \sa matPi(), matO(), join(), meet() */
struct TUncertainLine3
{
  Vec6 L = (Vec6() << 0, 0, 1, 0, 0, 0).finished();  ///< (L_h, L_0): the z axis by default
  Mat6 cov = Mat6::Zero();                           ///< covariance of L

  TUncertainLine3() = default;
  /** From a Plücker vector and its covariance (default: exact). */
  explicit TUncertainLine3(const Vec6& L_, const Mat6& cov_ = Mat6::Zero()) : L(L_), cov(cov_) {}

  /** The exact line through p with direction d: \f$ (\mathbf d, \mathbf p \times \mathbf d) \f$. */
  static TUncertainLine3 FromPointDirection(const Vec3& p, const Vec3& d);

  /** Direction part \f$ \mathbf L_h \f$. */
  Vec3 direction() const { return L.head<3>(); }
  /** Moment part \f$ \mathbf L_0 \f$. */
  Vec3 moment() const { return L.tail<3>(); }

  /** Relative violation of the Plücker constraint, \f$ \mathbf L_h^\top \mathbf L_0 / |\mathbf L|^2 \f$
   * (0 for a valid line). */
  double plueckerResidual() const;

  /** Point of the line closest to the origin, \f$ \mathbf L_h \times \mathbf L_0 / |\mathbf L_h|^2 \f$.
   * \throws std::runtime_error for a line at infinity (\f$ \mathbf L_h = 0 \f$). */
  Vec3 pointClosestToOrigin() const;

  /** Euclidean distance from p to the line, \f$ |\mathbf p \times \mathbf L_h - \mathbf L_0| /
   * |\mathbf L_h| \f$. \throws std::runtime_error for a line at infinity. */
  double distanceTo(const Vec3& p) const;

  /** Spherically normalized copy: \f$ \mathbf L / |\mathbf L| \f$ with \f$ J \Sigma J^\top \f$
   * (sphericallyNormalized()), then the covariance projected onto the tangent space of the Plücker
   * quadric, \f$ P \Sigma P^\top \f$ with \f$ P = I - \mathbf d \mathbf d^\top \f$,
   * \f$ \mathbf d = D\mathbf L / |D \mathbf L| \f$. For lines made by join()/meet() the projection
   * changes nothing (their covariance already has DL in its null space); for a line whose
   * covariance came from elsewhere it removes the direction that no valid line can move along,
   * which the rank counts of the hypothesis tests rely on. The value is not changed (see
   * plueckerCorrected()). The sign is kept (a join X ^ Y keeps its direction X -> Y).
   * \throws std::runtime_error for a zero or non-finite L. */
  TUncertainLine3 normalized() const;

  /** Like normalized(), after first moving L along \f$ D\mathbf L \f$ (the constraint's gradient) to
   * the nearest root of \f$ \mathbf L^\top D \mathbf L = 0 \f$; for lines not built by join()/meet(). */
  TUncertainLine3 plueckerCorrected() const;
};
}  // namespace immslam::geometry
