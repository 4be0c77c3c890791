/* imm-monoslam — camera motion models of the IMM bank (IMM paper Sec. I-B and V: stationary,
 * pure rotation with constant angular velocity, general motion with constant linear and angular
 * velocity), in the dimensionless formulation (paper ref. [2], doc/conventions.md).
 *
 * All models act on the same 13-D camera state x_v = (r, q, v, w): position r_W_C, orientation
 * q_W_C, linear velocity v (in W), angular velocity w (in C). A model that constrains a velocity to
 * zero does so through its transition (v' = 0 and/or w' = 0 with zero noise); the state layout is the
 * same for every model, so IMM mixing needs no padding (see doc/imm.md, "state conversion"). */
#pragma once

#include <immslam/math/types.h>

#include <string>

namespace immslam::motion
{
using Vec13 = Eigen::Matrix<double, 13, 1>;
using Mat13 = Eigen::Matrix<double, 13, 13>;

/** Offsets of the camera state blocks. */
constexpr int kR = 0, kQ = 3, kV = 7, kW = 10, kCamDim = 13;

/** The family of a motion model: what moves. */
enum class EMotionFamily
{
  Stationary,  ///< r' = r, v' = 0, w' = 0; q' = q (x) exp(W dt), W a zero-mean angular jitter (0 by default)
  Rotation,    ///< r' = r, v' = 0; q' = q (x) q((w + W) dt), w' = w + W: camera centre fixed
  General      ///< r' = r + (v + V) dt, q' = q (x) q((w + W) dt), v' = v + V, w' = w + W
};

/** Name of a family as used in configs and CSV headers ("stationary", "rotation", "general"). */
std::string familyName(EMotionFamily f);
/** Parses a family name; throws std::invalid_argument naming the word. */
EMotionFamily familyFromName(const std::string& name);

/** One motion model: its family and acceleration noise in pixels (IMM paper Sec. V: 0.1, 0.5, 1 px).
 * The impulses V = a dt and W = alpha dt have standard deviations sigma dt with
 * \f$ \sigma_a = \sigma_{a,px}/f \f$ and \f$ \sigma_\alpha = \sigma_{\alpha,px}/f \f$ (f = focal length
 * in pixels): the image motion such an acceleration causes on a feature at unit depth. */
struct TMotionModel
{
  EMotionFamily family = EMotionFamily::General;
  double sigmaLinearPx = 1.0;   ///< linear acceleration noise (general only), pixels
  double sigmaAngularPx = 1.0;  ///< angular acceleration noise (rotation, general), pixels; for the
                                ///< stationary model the std of a zero-mean angular jitter per frame
  std::string name;             ///< CSV column name, begins with the family name
  /** Std of a zero-mean angular shake of the camera per frame, pixels (a random walk of the
   * orientation on top of the model's motion, not kept in the angular velocity: hand tremor, vibration).
   * The same in every model of a bank, so a still camera is the rotation model's special case w = 0
   * and the stationary model (no velocity to learn) stays the simpler explanation (doc/imm.md). For the
   * stationary model it adds to sigmaAngularPx, its own jitter. */
  double shakePx = 0.0;

  /** "general_1px", "rotation_0.5px", "stationary" when name is empty. */
  std::string displayName() const;
};

using Mat36u = Eigen::Matrix<double, 3, 6>;
using Mat46u = Eigen::Matrix<double, 4, 6>;
using Vec6u = Eigen::Matrix<double, 6, 1>;
using Mat6u = Eigen::Matrix<double, 6, 6>;

/** The camera motion of one prediction step in the camera-centred (robocentric) formulation,
 * where the velocities u = (v, w) are both expressed in the current camera frame C_k:
 * the camera moves to C_{k+1} with \f$ p_{C_k} = R(dq)\, p_{C_{k+1}} + t \f$,
 * \f$ t = (v + V)\,dt \f$ (general only) and \f$ dq = \exp((w + W)\,dt) \f$ (rotation, general), and the
 * velocities become \f$ u' = (R(dq)^\top (v + V),\; w + W) \f$ (general), \f$ (0, w + W) \f$ (rotation) or
 * 0 (stationary). The impulses (V, W) enter exactly like a perturbation of u, so the Jacobians with
 * respect to u are also those with respect to the noise, whose covariance is `noiseCov`. */
struct TMotionIncrement
{
  Vec3 t = Vec3::Zero();
  Vec4 dq = Vec4(1, 0, 0, 0);
  Mat36u J_t_u = Mat36u::Zero();
  Mat46u J_dq_u = Mat46u::Zero();
  Vec6u uNext = Vec6u::Zero();
  Mat6u J_uNext_u = Mat6u::Zero();
  Mat6u noiseCov = Mat6u::Zero();  ///< covariance of (V, W) in state units
  /** Stationary: nothing moves on average (the velocities do not act and become 0). A non-zero
   * noiseCov is then a zero-mean jitter entering through J_t_n / J_dq_n instead of through u. */
  bool identity = false;
  Mat36u J_t_n = Mat36u::Zero();   ///< stationary jitter: dt/d(noise)
  Mat46u J_dq_n = Mat46u::Zero();  ///< stationary jitter: d(dq)/d(noise)
  /** Rotation, general: covariance of the shake, a zero-mean rotation exp(s) of the camera after the
   * motion (pose and features re-expressed through it, velocities unchanged): shakePx^2 / f^2 dt. */
  Mat3 shakeCov = Mat3::Zero();
};

/** The increment of model m over dt frames from the velocities (v, w) in the camera frame. */
TMotionIncrement motionIncrement(const TMotionModel& m, const Vec3& v, const Vec3& w, double dt, double focalPx);
}  // namespace immslam::motion
