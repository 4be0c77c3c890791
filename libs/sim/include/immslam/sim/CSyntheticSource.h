/* imm-monoslam — the built-in renderer as an image source (the main app's default input). */
#pragma once

#include <immslam/io/CImageSource.h>
#include <immslam/sim/CSimulator.h>

#include <memory>
#include <string>
#include <vector>

namespace immslam::sim
{
/** Renders the frames of a scenario on the fly (no files), with the scenario's calibration and
 * ground truth, and the per-frame truth the evaluation needs: motion labels, object poses and
 * object masks. */
class CSyntheticSource : public io::CImageSource
{
 public:
  /** \param maxFrames stop after this many frames (0: the whole script). */
  explicit CSyntheticSource(std::shared_ptr<const CSimulator> sim, std::size_t maxFrames = 0);

  /** Renders a scenario (e.g. TScenario::builtinDefault()). */
  explicit CSyntheticSource(TScenario scenario, std::size_t maxFrames = 0);

  /** Loads a scenario file (with `SECTION.KEY=VALUE` overrides) and renders it.
   * \throws std::runtime_error naming the file/key at fault. */
  explicit CSyntheticSource(const std::string& scenarioPath, const std::vector<std::string>& overrides = {},
                            std::size_t maxFrames = 0);

  io::ENextStatus next(io::TFrame& frame, std::string& why) override;
  camera::CCameraModel::Ptr calibration() const override { return m_sim->camera(); }
  std::optional<core::TTrajectory> groundTruth() const override { return m_sim->groundTruth(m_count); }
  std::string describe() const override;
  std::size_t sizeHint() const override { return m_count; }

  const CSimulator& simulator() const { return *m_sim; }

  /** True motion label of frame k. */
  EMotionLabel label(std::size_t k) const { return m_sim->motionLabel(k); }

  /** T_W_O of the moving objects at frame k. */
  std::vector<TObjectPose> objectPoses(std::size_t k) const { return m_sim->objectPoses(k); }

  /** Object mask of frame k (kept from the last next() when it was frame k, else rendered). */
  cv::Mat mask(std::size_t k) const;

 private:
  std::shared_ptr<const CSimulator> m_sim;
  std::size_t m_count = 0;
  std::size_t m_next = 0;
  std::size_t m_lastIndex = static_cast<std::size_t>(-1);
  cv::Mat m_lastMask;
};
}  // namespace immslam::sim
