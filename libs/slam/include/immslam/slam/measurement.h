/* imm-monoslam — the measurement model of the camera-centred SLAM filter: every feature is
 * expressed in the current camera frame (the camera is the origin), so a feature's pixel depends on
 * its own block only: \f$ h = \mathrm{proj}(\rho x_0 + m(\theta,\phi)) \f$ (inverse depth) or
 * \f$ \mathrm{proj}(p) \f$ (XYZ), distortion included. Jacobians are never evaluated at an uncertain
 * camera pose (the reason for the camera-centred form: consistency, doc/estimator.md). */
#pragma once

#include <immslam/bayes/ekf_update.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/slam/TFeature.h>

namespace immslam::slam
{
/** 2x6 (inverse depth) or 2x3 (XYZ), without heap allocation. */
using Mat2F = Eigen::Matrix<double, 2, Eigen::Dynamic, Eigen::RowMajor, 2, 6>;

/** The pixel of feature f in state x. \param J_feat dh/d(feature block).
 * \return false if the point is behind the camera or outside the model's valid domain. */
bool predictMeasurement(const camera::CCameraModel& cam, const VecX& x, const TFeature& f, Vec2& uv,
                        Mat2F* J_feat = nullptr);

/** Euclidean point of the feature in the current camera frame (inverse-depth features with rho
 * clamped to >= rhoMin, so a point at infinity becomes a far point along its ray). */
Vec3 featurePointInCamera(const VecX& x, const TFeature& f, double rhoMin = 1e-3);

/** \f$ S = H P H^\top + \sigma^2 I \f$ for one feature: H touches its block only, so only the
 * feature's own covariance block Pff is needed (exactly symmetric result). */
Mat2 innovationCovariance(const Eigen::Ref<const MatX>& Pff, const Mat2F& J_feat, double sigmaPixel);

/** T_W_C of the state's world-pose block (r_CW, q_CW = T_C_W):
 * \f$ q_{WC} = \bar q_{CW},\; r_{WC} = -R(q_{WC})\, r_{CW} \f$. \param J d(r_WC, q_WC)/d(r_CW, q_CW) (7x7). */
void worldPoseFromState(const VecX& x, Vec3& r_WC, Vec4& q_WC, Eigen::Matrix<double, 7, 7>* J = nullptr);
}  // namespace immslam::slam
