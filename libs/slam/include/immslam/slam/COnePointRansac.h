/* imm-monoslam — 1-point RANSAC for EKF filtering (Civera, Grasa, Davison & Montiel, JFR 2010):
 * the mismatch rejection of the SLAM filter.
 *
 * Why 1-point RANSAC and not JCBB: the EKF prior leaves one degree of freedom of the hypothesis
 * to be fixed by data, so a single match (with the prior) instantiates a full state hypothesis;
 * the number of hypotheses is tiny (about 7 for 50 % outliers at p = 0.99, adaptive), each costs
 * O(n) (a mean-only update and a re-projection), whereas JCBB's branch and bound is exponential in
 * the worst case over ~30-40 matches per frame and needs a Mahalanobis test per node with the
 * full joint covariance. Measured on our sequences in doc/performance.md. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/slam/measurement.h>

#include <mrpt/config/CLoadableOptions.h>

#include <functional>
#include <random>
#include <vector>

namespace immslam::slam
{
/** A match proposed by the active search, with the fused prediction it was found from. */
struct TCandidate
{
  int feature = -1;          ///< index into the feature list
  Vec2 z = Vec2::Zero();     ///< measured pixel
  Vec2 h = Vec2::Zero();     ///< predicted pixel h(x_hat)
  Mat2F J_feat;
  Mat2 S = Mat2::Identity(); ///< innovation covariance at (x_hat, P_hat)
  /** Found only by the search for a feature that may have started to move, outside its 95 % ellipse
   * (CSlamTracker::searchFeatures): never used in an update, it counts as a rejection. */
  bool outsideGate = false;
};

class COnePointRansac
{
 public:
  struct TOptions : public mrpt::config::CLoadableOptions
  {
    double inlier_threshold_px = 2.0;  ///< |z - h(x_hyp)| below this: supports the hypothesis
    // Not configuration keys (internal constants of 1-point RANSAC, Civera et al., JFR 2010; doc/estimator.md); the
    // fields stay for tests and library users.
    static constexpr double kSuccessProbability = 0.99;  ///< p of at least one all-inlier hypothesis
    static constexpr int kMaxHypotheses = 200;           ///< cap of the adaptive number of hypotheses
    static constexpr double kRescueProbability = 0.99;   ///< chi-square (2 dof) gate of the rescue
    double success_probability = kSuccessProbability; ///< p in n_hyp = log(1-p)/log(1-eps)
    int max_hypotheses = kMaxHypotheses;              ///< upper bound on the adaptive number of hypotheses
    double rescue_probability = kRescueProbability;   ///< chi-square (2 dof) gate of the high-innovation rescue
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
    void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;
    /** \throws std::runtime_error naming the key of a value out of range. */
    void validate(const std::string& section) const;
  };

  COnePointRansac();
  explicit COnePointRansac(const TOptions& o) : m_opts(o) {}
  const TOptions& options() const { return m_opts; }

  /** Low-innovation inliers: the candidates (indices) supporting the best of the adaptive number of
   * 1-point hypotheses \f$ x_i = \hat x + K_i (z_i - h_i(\hat x)) \f$, \f$ K_i = \hat P H_i^\top S_i^{-1} \f$.
   * \param nHypotheses optional output: hypotheses tried. */
  /** \param covColumns returns the columns [off, off+len) of the (fused) predicted covariance. */
  std::vector<int> lowInnovationInliers(const camera::CCameraModel& cam, const VecX& x,
                                        const std::function<MatX(int, int)>& covColumns,
                                        const std::vector<TFeature>& features,
                                        const std::vector<TCandidate>& cands, std::mt19937& rng,
                                        int* nHypotheses = nullptr) const;

 private:
  TOptions m_opts;
};
}  // namespace immslam::slam
