/* imm-monoslam — conversions between the project's frames/parametrizations and MRPT's viewer
 * objects (poses, inverse-depth ellipsoids, colours). */
#pragma once

#include <immslam/core/TTrajectory.h>
#include <immslam/math/types.h>
#include <immslam/viz/colours.h>
#include <immslam/viz/scene.h>

#include <mrpt/img/TColor.h>
#include <mrpt/poses/CPose3D.h>

namespace immslam::viz
{
/** T_W_C of a stamped pose as an MRPT pose (same frames: W and the optical frame C). */
mrpt::poses::CPose3D toMrptPose(const core::TStampedPose& pose);

/** T_C_B: the MRPT "body" frame B (x forward, y left, z up) of a camera, expressed in its optical
 * frame C. MRPT objects that look along +X (CFrustum, ...) are placed at T_W_C (+) T_C_B.
 * It is the inverse of CPose3D(0,0,0,-90deg,0,-90deg) = T_B_C, which maps optical coordinates to
 * MRPT's (doc/conventions.md). */
mrpt::poses::CPose3D opticalToMrptBody();

/** T_D_W: the z-up display frame D (MRPT convention) from the world W (optical-like, y down). */
mrpt::poses::CPose3D displayFromWorld();

/** An inverse-depth feature as MRPT's CEllipsoidInverseDepth3D wants it. */
struct TMrptInverseDepth
{
  mrpt::poses::CPose3D pose;  ///< object pose in W: at the anchor, rotated (see inverseDepthToMrpt)
  Vec3 mean = Vec3::Zero();   ///< (inv_range, yaw, pitch)
  Mat3 cov = Mat3::Zero();    ///< covariance of (inv_range, yaw, pitch) (not yet compensated)
};

/** Converts (x0, theta, phi, rho) and cov(theta, phi, rho) to MRPT's parametrization.
 *
 * MRPT 2.5.8 maps (inv_range, yaw, pitch) to the object-frame point
 * \f$ \frac{1}{\rho}(\cos y\cos p,\; \sin y\cos p,\; -\sin p) \f$ (and to the range
 * getUnderflowMaxRange() when inv_range < 0). With the object rotated by
 * \f$ R = [e_y\; e_z\; e_x] \f$ (object x -> W z, object y -> W x, object z -> W y) this is exactly
 * our \f$ m(\theta,\phi)/\rho \f$ with yaw = theta and pitch = phi, so the map is linear (a
 * permutation): mean = (rho, theta, phi) and the covariance is permuted accordingly. */
TMrptInverseDepth inverseDepthToMrpt(const TInverseDepthView& f);

/** The matrix to pass to setCovMatrix() of an MRPT 2.5.8 CGeneralizedEllipsoidTemplate<3>
 * (CEllipsoid3D, CEllipsoidInverseDepth3D) so that the drawn surface is the iso-surface of C.
 *
 * MRPT computes the upper Cholesky factor U (M = U^T U) of the matrix M it is given but then draws
 * mean + U s for unit vectors s, i.e. the ellipsoid of U U^T, which differs from M when M has
 * off-diagonal terms. We pass \f$ M = U'^T U' \f$ with \f$ U' = P L P \f$ upper triangular, where
 * P reverses the order of the axes and \f$ L L^T = P C P \f$ (lower Cholesky): then MRPT's factor
 * of M is U' and it draws \f$ U' U'^T = C \f$.
 * \return M, or a zero matrix if C is not finite and positive definite. */
Mat3 mrptEllipsoidCovariance(const Mat3& C);

/** Our colour as MRPT's (opaque unless alpha is given). */
mrpt::img::TColor toMrptColour(const TColour& c, std::uint8_t alpha = 255);
}  // namespace immslam::viz
