/* imm-monoslam — prediction of the camera-centred SLAM state (Civera et al.'s camera-centred EKF):
 * the camera moves by the increment of its motion model and the whole state is re-expressed in the
 * new camera frame: the world pose T_C_W, the velocities and every feature. */
#pragma once

#include <immslam/bayes/CIMMEstimator.h>
#include <immslam/bayes/ekf_update.h>
#include <immslam/motion/motion_models.h>
#include <immslam/slam/TFeature.h>

#include <vector>

namespace immslam::slam
{
/** Stochastic cloning of past camera poses (CImmSlamFilter::clonePose): clone c is the pose
 * T_C_Cj = (r, q) of a past camera C_j seen from the current camera, 7 states at poseCloneOffset(c),
 * between the velocities and the first feature. It is born at the identity with no covariance (C_j is
 * the current camera) and every prediction re-expresses it as it does the world pose T_C_W; the
 * updates then correlate it with the current pose, so the relative pose between the two comes with
 * its own covariance (Roumeliotis & Burdick 2002; the MSCKF's clones, in the camera-centred frame).
 * Every function below takes the number of clones (0: none). */
constexpr int kPoseCloneDim = 7;
constexpr int poseCloneOffset(int c) { return motion::kCamDim + kPoseCloneDim * c; }

/** \f$ x' = f(x, u + n) \f$ and \f$ P' = A (P + E N E^\top) A^\top \f$, with A = df/dx block-structured
 * (each block depends on itself and on the velocities u only), computed block by block in
 * O(n sum_b (s_b^2 + 6 s_b)). The stationary model leaves the map and world pose untouched and zeroes
 * the velocities. \param scratch an n x n buffer reused between calls. \param lowerInput only the
 * lower triangle of g.P is valid (bayes::CIMMEstimator::mix with lowerOnly): the few upper parts the
 * transition reads are completed first (mirrorTransitionInputs()); the result is the same, bitwise. */
void predictRobocentric(bayes::TGaussian& g, const std::vector<TFeature>& features,
                        const motion::TMotionIncrement& inc, MatX& scratch, bool lowerInput = false, int nClones = 0);

/** Relocalisation (relocalise.h): the camera is found at T_C'W = (r_CW_new, q_CW_new) instead of the
 * state's T_CW. The whole camera-centred state is re-expressed in C' as by a prediction step whose
 * increment is T_CC' (dq = q_CW (x) conj(q_CW_new), t = r_CW - R(dq) r_CW_new): the world positions
 * of the features do not change, their camera-frame coordinates and covariances follow. The found
 * pose's own uncertainty enters like the impulses of a motion model, a translation error of std
 * sigmaT and a rotation error of std sigmaTheta (rad) of C'. The velocities, unknown after a loss of
 * tracking, restart at `velocity` (v, w in C', per frame) with the covariance velocityCov
 * (cross-covariances zero).
 * \param scratch an n x n buffer reused between calls. */
void applyPoseCorrection(bayes::TGaussian& g, const std::vector<TFeature>& features, const Vec3& r_CW_new,
                         const Vec4& q_CW_new, double sigmaT, double sigmaTheta, const Vec6& velocity,
                         const Mat6& velocityCov, MatX& scratch, int nClones = 0);
/** One block row of the transition A: rows [off, off + len) of A hold D (len x len) on the block's own
 * columns and, if hasG, G (len x 6) on the velocity columns u; zeros elsewhere (len <= 7). */
struct TTransitionBlock
{
  int off = 0, len = 0;
  bool hasG = true;
  Eigen::Matrix<double, 7, 7> D = Eigen::Matrix<double, 7, 7>::Zero();
  Eigen::Matrix<double, 7, 6> G = Eigen::Matrix<double, 7, 6>::Zero();
};

/** The prediction of a moving model (inc.identity false) split in two, so the covariance part can be
 * deferred (lazy modes of the IMM, CMonoSlamIMM): the mean x' = f(x, u), the transition blocks of A
 * (the world pose, the velocities, then one block per feature in `features` order) and
 * P~ = P + E N E^T (in place). predictRobocentric() = this + applyRobocentricTransition(). */
void predictRobocentricMean(bayes::TGaussian& g, const std::vector<TFeature>& features,
                            const motion::TMotionIncrement& inc, std::vector<TTransitionBlock>& blocks,
                            int nClones = 0);
/** P <- A P~ A^T (exactly symmetric), about half of O(n sum_b (s_b^2 + 6 s_b)): only the lower block
 * triangle is computed, then mirrored (unless !mirror: the caller reads the lower triangle only, e.g.
 * a rank update before its own mirror). \p scratch: an n x 13 work buffer. */
void applyRobocentricTransition(MatX& P, const std::vector<TTransitionBlock>& blocks, MatX& scratch,
                                bool mirror = true);
/** Completes, from the lower triangle, the parts of the strictly upper triangle of P that
 * applyRobocentricTransition() reads besides the lower triangle: the rows of the velocities u (7..12)
 * right of the diagonal, the world pose's rows in the columns of u, and every diagonal block (pose,
 * u, each feature of `features`). O(n). */
void mirrorTransitionInputs(MatX& P, const std::vector<TFeature>& features, int nClones = 0);
/** n x 3 factor F, F F^T = B N B^T: the covariance a zero-mean shake of the camera (a rotation exp(s)
 * after the motion, s ~ N(0, shakeCov), motion::TMotionIncrement::shakeCov) adds to the predicted state g
 * (pose and features re-expressed through it; the velocities are not changed). */
MatX shakeFactor(const bayes::TGaussian& g, const std::vector<TFeature>& features, const Mat3& shakeCov,
                 int nClones = 0);
/** P <- P + F F^T, exactly symmetric. */
void addCovarianceFactor(MatX& P, const MatX& F);
/** Columns of block b of A P~ A^T (n x len_b), without forming it: O(n len_b (len_b + 6)). */
MatX transitionColumns(const MatX& Pt, const std::vector<TTransitionBlock>& blocks, int b);
/** Diagonal block of A P~ A^T for one transition block: O(len^2 (len + 6)). */
MatX transitionBlock(const MatX& Pt, const TTransitionBlock& blk);
/** H A P~ A^T H^T for a measurement Jacobian whose blocks each lie on one transition block (the
 * features): O(n m (len + 6)) instead of the O(n^2) of forming A P~ A^T. \param blockAt transition block
 * index of each state offset (-1 elsewhere). 	hrows std::logic_error if a block of H is not one
 * transition block. */
MatX transitionInnovationCovariance(const MatX& Pt, const std::vector<TTransitionBlock>& blocks,
                                    const std::vector<int>& blockAt, const bayes::CSparseJacobian& H);
}  // namespace immslam::slam
