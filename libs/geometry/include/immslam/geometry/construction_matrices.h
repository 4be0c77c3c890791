/* imm-monoslam — construction matrices of uncertain projective geometry (shadow-filter paper,
 * eqs. (6)-(10), after Heuel, "Uncertain Projective Geometry", LNCS 3008, 2004, ch. 3).
 *
 * Every join/meet is bilinear, z = U(x) y = V(y) x (eq. (10)), so U(x) = dz/dy and V(y) = dz/dx.
 * With points X = (X0, Xh), planes A = (Ah, A0), lines L = (Lh, L0) (TUncertainLine3 documents the
 * Plücker convention) and the dualization D (swap of Lh and L0):
 *
 * | construction                  | z = U(x) y        | U = dz/dy   | V = dz/dx      |
 * |-------------------------------|-------------------|-------------|----------------|
 * | line  L = X ^ Y      (eq. 6)  | Pi(X) Y           | Pi(X)       | -Pi(Y)         |
 * | plane A = X ^ L      (eq. 8)  | O(L) X            | O(L) (=dA/dX)| -PiBar(X)^T (=dA/dL) |
 * | line  L = A meet B            | PiBar(A) B        | PiBar(A)    | -PiBar(B)      |
 * | point X = L meet A            | OBar(L) A         | OBar(L) (=dX/dA) | -Pi(A)^T (=dX/dL) |
 *
 * Duality: a plane is to a point what D L is to L. Meeting two planes is joining them "as points"
 * and dualizing the result, PiBar(A) = D Pi(A); meeting a line with a plane is joining the plane
 * "as a point" with the dual line, OBar(L) = O(D L). All of it is derived in the .cpp and checked
 * against numerical Jacobians in geometry_unittest.
 */
#pragma once

#include <immslam/geometry/geometry_types.h>

namespace immslam::geometry
{
/** \f$ \Pi(\mathbf X) \f$ of eq. (7) (6x4): \f$ \mathbf X \wedge \mathbf Y = \Pi(\mathbf X)\mathbf Y \f$,
 * \f[ \Pi(\mathbf X) = \begin{pmatrix} X_h I_3 & -\mathbf X_0 \\ [\mathbf X_0]_\times & \mathbf 0
 *     \end{pmatrix}. \f]
 * Also the Jacobian of the join w.r.t. Y; w.r.t. X it is \f$ -\Pi(\mathbf Y) \f$.
 * Applied to a plane, \f$ -\Pi(\mathbf A)^\top \f$ is the Jacobian of L meet A w.r.t. L. */
Mat64 matPi(const Vec4& X);

/** \f$ \bar\Pi(\mathbf A) = D\,\Pi(\mathbf A) \f$ (6x4): the meet of two planes is the line
 * \f$ \mathbf A \cap \mathbf B = \bar\Pi(\mathbf A)\mathbf B =
 * (\mathbf A_h \times \mathbf B_h,\; A_0 \mathbf B_h - B_0 \mathbf A_h) \f$ (direction along the
 * intersection, moment p x direction for p on both planes),
 * \f[ \bar\Pi(\mathbf A) = \begin{pmatrix} [\mathbf A_h]_\times & \mathbf 0 \\ A_0 I_3 & -\mathbf A_h
 *     \end{pmatrix}. \f]
 * Applied to a point, \f$ -\bar\Pi(\mathbf X)^\top \f$ is the Jacobian of X ^ L w.r.t. L. */
Mat64 matPiBar(const Vec4& A);

/** The dualization \f$ D = \begin{pmatrix} 0 & I_3 \\ I_3 & 0 \end{pmatrix} \f$ (6x6): swaps the
 * direction and moment parts. \f$ D\mathbf L \f$ is the same line in dual (plane-meet) coordinates;
 * \f$ \mathbf L^\top D \mathbf M = \mathbf L_h^\top \mathbf M_0 + \mathbf L_0^\top \mathbf M_h \f$
 * vanishes iff the lines are coplanar (the Plücker constraint is \f$ \mathbf L^\top D\mathbf L = 0 \f$). */
Mat6 matDual();

/** \f$ D\mathbf L = (\mathbf L_0, \mathbf L_h) \f$, the dual Plücker operator applied to L. */
Vec6 dualLine(const Vec6& L);

/** \f$ O(\mathbf L) \f$ of eq. (9) as printed (4x4): the plane through X and L is
 * \f$ \mathbf X \wedge \mathbf L = O(\mathbf L)\mathbf X =
 * (\mathbf X_0 \times \mathbf L_h - X_h \mathbf L_0,\; \mathbf L_0^\top \mathbf X_0) \f$,
 * \f[ O(\mathbf L) = \begin{pmatrix} -[\mathbf L_h]_\times & -\mathbf L_0 \\ \mathbf L_0^\top & 0
 *     \end{pmatrix}. \f]
 * It vanishes on the points of L (\f$ O(\mathbf L)\mathbf X = 0 \iff \mathbf X \in \mathbf L \f$);
 * its column space is the pencil of planes through L (rank 2 for a valid line). */
Mat4 matO(const Vec6& L);

/** \f$ \bar O(\mathbf L) = O(D\mathbf L) \f$ (4x4): the point where L meets the plane A is
 * \f$ \mathbf L \cap \mathbf A = \bar O(\mathbf L)\mathbf A =
 * (\mathbf A_h \times \mathbf L_0 - A_0 \mathbf L_h,\; \mathbf L_h^\top \mathbf A_h) \f$,
 * \f[ \bar O(\mathbf L) = \begin{pmatrix} -[\mathbf L_0]_\times & -\mathbf L_h \\ \mathbf L_h^\top & 0
 *     \end{pmatrix}. \f]
 * It vanishes on the planes through L; its column space is the range of points of L. */
Mat4 matOBar(const Vec6& L);
}  // namespace immslam::geometry
