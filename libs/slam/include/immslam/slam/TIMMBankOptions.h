/* imm-monoslam — options of the IMM bank of motion models (section [imm]): the models, the Markov
 * matrix, the prior, the probability floor and the bank's own policy (dormant modes, lazy prediction).
 * Read by CImmSlamFilter (paper Fig. 2, eq. 7). */
#pragma once

#include <immslam/math/types.h>
#include <immslam/motion/motion_models.h>

#include <mrpt/config/CLoadableOptions.h>

#include <string>
#include <vector>

namespace immslam::slam
{
/** Motion model bank of the IMM (section [imm]). */
struct TIMMBankOptions : public mrpt::config::CLoadableOptions
{
  /** Diagonal of the default Markov matrix (eq. 7's pi; not a configuration key: [imm] transition_matrix
   * gives any other matrix). */
  static constexpr double kTransitionStay = 0.995;
  /** Floor of every model probability (not a configuration key; doc/imm.md). */
  static constexpr double kProbabilityFloor = 1e-4;
  /** Space-separated model specs: `stationary`, `rotation:SIGMA_ANG_PX`,
   * `general:SIGMA_PX` or `general:SIGMA_LIN_PX:SIGMA_ANG_PX`. */
  std::string models = "stationary rotation:0.1 rotation:0.5 rotation:1 general:0.1 general:0.5 general:1";
  /** r x r row-major Markov matrix pi(j, i) = P(i at k | j at k-1); empty: built from transition_stay. */
  std::vector<double> transition_matrix;
  /** Diagonal of the default Markov matrix. The rest of a general mode's row is spread evenly over the
   * other modes; a mode whose linear velocity is fixed at 0 (stationary, rotation) spreads
   * (1 - transition_stay) / (r - 1) over the non-general modes only and keeps the remainder on the
   * diagonal: no Markov switch into a general mode, which then keeps its own history (mixing from a
   * mode with v = 0 and zero variance would pull its velocity, which carries the scale of a monocular
   * map, back to 0 every frame) and takes over by the likelihood of the measurements from the
   * probability floor (doc/imm.md, "Entering the general modes"). */
  double transition_stay = kTransitionStay;
  /** Initial model probabilities (empty: uniform). */
  std::vector<double> prior;
  /** Lower bound of every model probability (no model dies for ever). */
  double probability_floor = kProbabilityFloor;
  /** Dormant modes (a model-set adaptation in the spirit of Li's variable-structure IMM; 0 = the exact
   * IMM, every mode updated). After the likelihoods of the frame's low-innovation matches are known, a
   * mode whose probability given them, mu_{k|k-1} L^(1) normalized, is below this value is dormant for
   * the frame: its likelihood of **all** the frame's measurements is still computed exactly (eq. 3,
   * from its own prediction, so it can win back probability at once), but its covariance is not
   * updated (the O(n^2 m) step); after the probability update it takes the posterior of the most
   * probable updated mode of an equal or richer family (general > rotation > stationary; one mode of
   * each richer family present is kept updated). A dormant mode ends the frame at the floor, where its
   * own history weighs ~pi_ii floor / mu_{k|k-1} (~0.1 with the defaults) in its next mixing. Measured
   * (doc/imm.md): 1e-5 gave the exact IMM's ATE within 2.3 % on 9 of 11 rendered sequences (better on 2);
   * 1e-4 failed on one of them (3.1 % vs 0.75 % of path), 1e-3 on another (9.4 % vs 1.2 %). */
  double dormant_below = 1e-5;
  /** Lazy prediction (with dormant_below > 0): a moving mode that was dormant in the previous frame gets
   * its predicted mean and the blocks of its transition only; the blocks of its predicted covariance
   * that the frame reads (search regions, RANSAC columns, its likelihood) are computed from them in
   * O(n) each, and the O(n^2) covariance prediction runs only if the frame makes it active. Exact: the
   * same numbers as the full prediction, up to rounding. Not a configuration key (it is exact): the
   * field lets the tests compare it with the full prediction. */
  bool lazy_prediction = true;
  /** Zero-mean angular shake of the camera, px per frame (std of a random walk of the orientation,
   * shake_px / f sqrt(dt) rad), in every model: after the stationary model's identity, the rotation
   * and general models' constant-velocity step (motion::TMotionModel::shakePx; doc/imm.md, "Camera
   * shake"). 0 = none (the paper's models). */
  double shake_px = 0.15;

  void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
  void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;

  /** The parsed models. \throws std::runtime_error naming [imm] models. */
  std::vector<motion::TMotionModel> parseModels() const;
  /** The Markov matrix (r x r). \throws std::runtime_error naming the key. */
  MatX transitionMatrix(int r) const;
  VecX priorProbabilities(int r) const;
};
}  // namespace immslam::slam
