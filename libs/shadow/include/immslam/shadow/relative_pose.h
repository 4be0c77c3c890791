/* imm-monoslam — uncertain rigid transforms composed from the SLAM filter's frame-to-frame
 * increments: the relative motion between the views of a shadow feature, with its covariance. */
#pragma once

#include <immslam/math/types.h>

namespace immslam::shadow
{
/** An uncertain rigid transform \f$ T_{AB} \f$: \f$ p_A = R(q)\,p_B + t \f$, q = [qw qx qy qz].
 * The error is the perturbation \f$ \delta = [\delta t; \delta\theta] \f$ with
 * \f$ t = \hat t + \delta t \f$ (in A) and \f$ R = \hat R\,\mathrm{Exp}(\delta\theta) \f$ (in B),
 * cov its 6x6 covariance (the convention of TCameraMotion). */
struct TUncertainPose
{
  Vec3 t = Vec3::Zero();
  Vec4 q = Vec4(1, 0, 0, 0);
  Mat6 cov = Mat6::Zero();

  /** R(q). */
  Mat3 rotation() const;
  /** The inverse transform's mean \f$ T_{BA} \f$ (cov not propagated, left zero). */
  TUncertainPose inverseMean() const;
  /** Maps a point of B into A. */
  Vec3 transform(const Vec3& p_B) const;
};

/** Composition \f$ T_{AC} = T_{AB}\,T_{BC} \f$ of two independent uncertain transforms:
 * \f$ t = t_a + R_a t_b \f$, \f$ R = R_a R_b \f$ and, to first order,
 * \f$ \delta = J_a \delta_a + J_b \delta_b \f$ with
 * \f[ J_a = \begin{pmatrix} I & -R_a [t_b]_\times \\ 0 & R_b^\top \end{pmatrix},\quad
 *     J_b = \begin{pmatrix} R_a & 0 \\ 0 & I \end{pmatrix}, \f]
 * cov \f$ = J_a \Sigma_a J_a^\top + J_b \Sigma_b J_b^\top \f$ (the increments of consecutive frames
 * taken as independent). The quaternion is re-normalized.
 * \param J_ab_a, J_ab_b optional 6x6 Jacobians. */
TUncertainPose composePoses(const TUncertainPose& a, const TUncertainPose& b, Mat6* J_ab_a = nullptr,
                            Mat6* J_ab_b = nullptr);

/** Transport of a perturbation along a chain: for \f$ T_{0k} = T_{0m}\,T_{mk} \f$ with
 * \f$ T_{mk} \f$ the part composed after view m, \f$ \delta_k = \Phi\,\delta_m + \nu \f$ where
 * \f$ \nu \f$ (the increments after m) is independent of \f$ \delta_m \f$, so
 * \f$ \mathrm{Cov}(\delta_k, \delta_m) = \Phi\,\Sigma_m \f$. With \f$ T_{mk} = T_{0m}^{-1} T_{0k} \f$
 * (from the means):
 * \f$ \Phi = \begin{pmatrix} I & -R_{0m} [t_{mk}]_\times \\ 0 & R_{mk}^\top \end{pmatrix} \f$. */
Mat6 perturbationTransport(const TUncertainPose& T0m, const TUncertainPose& T0k);

/** The perturbation \f$ [\,t - \hat t;\ \mathrm{Log}(\hat R^\top R)\,] \f$ of a transform (t, q)
 * w.r.t. the estimate (tHat, qHat) (for tests and simulations). */
Vec6 posePerturbation(const Vec3& tHat, const Vec4& qHat, const Vec3& t, const Vec4& q);

/** The transform (tHat + dt, qHat (x) Exp(dtheta)) for a perturbation [dt; dtheta]. */
TUncertainPose perturbPose(const TUncertainPose& T, const Vec6& delta);
}  // namespace immslam::shadow
