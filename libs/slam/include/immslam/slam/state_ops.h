/* imm-monoslam — structural operations on one mode-conditioned Gaussian of the SLAM state:
 * feature initialisation (augmentation), deletion and inverse-depth -> XYZ conversion
 * (re-parametrization), quaternion normalization. The IMM bank applies each one to every mode
 * with that mode's own linearization point, so all modes keep the same layout. */
#pragma once

#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/math/types.h>

#include <vector>

namespace immslam::slam
{
/** One new inverse-depth feature to append: its ray in the camera frame and d(ray)/d(uv). */
struct TNewRay
{
  Vec3 b_C = Vec3::UnitZ();
  Mat32 J_b_uv = Mat32::Zero();
  /** Prior on inverse depth (mean, standard deviation): (rho_0, sigma_rho) in the paper's
   * dimensionless formulation; a shadow-filter promotion passes its own estimate. */
  double rho = 1.0, sigmaRho = 1.0;
  /** Standard deviation of the pixel the ray comes from. */
  double sigmaPixel = 1.0;
};

/** Undelayed inverse-depth initialisation (Civera et al.) in the camera-centred state: the anchor is
 * the current camera centre (the origin, exactly known), so y = (0, theta(b(uv)), phi(b(uv)), rho) with
 * \f$ P_{yy} = G_{uv} \sigma^2 G_{uv}^\top + \sigma_\rho^2 e_6 e_6^\top \f$ and no cross-covariance. */
void appendInverseDepthFeatures(bayes::TGaussian& g, const std::vector<TNewRay>& rays);

/** A piece of the new state in terms of the old one: a copy of an old range, or a new block
 * f(old range) given by its value and Jacobian (first-order covariance transfer). */
struct TReparamSegment
{
  int oldOffset = 0, oldLen = 0;
  bool copy = true;
  VecX newValue;  ///< when !copy
  MatX J;         ///< d(newValue)/d(old range), newValue.size() x oldLen, when !copy
  int newLen() const { return copy ? oldLen : static_cast<int>(newValue.size()); }
};

/** Rebuilds (x, P) from segments (old ranges not mentioned are dropped: feature deletion):
 * \f$ P'_{ab} = T_a P_{ab} T_b^\top \f$ with T the identity for copies. */
void reparametrize(bayes::TGaussian& g, const std::vector<TReparamSegment>& segs);

/** The inverse T_Cj_C of a pose clone T_C_Cj = (r, q) (p_C = R(q) p_Cj + r; q need not be unit) with
 * its 7x7 covariance P in the state's (r, q): t = -R^T r, qInv = conj(q) (normalized) and the covariance
 * of [dt; dtheta] (t = t_hat + dt, R = R_hat Exp(dtheta)). Chain rule: the clone's perturbation
 * b = dr, a = 2 vec(conj(q_hat) (x) dq) / |q| (q_hat = q / |q|), then dt = -R^T b + [t]x a, dtheta = -R a. */
void invertPoseClone(const Vec3& r, const Vec4& q, const MatX& P, Vec3& t, Vec4& qInv, Mat6& cov);

/** q <- q/|q| for the camera quaternion (state 3..6) with \f$ P \leftarrow J P J^\top \f$. */
void normalizeQuaternion(bayes::TGaussian& g);
}  // namespace immslam::slam
