/* imm-monoslam — the full system of the two papers wired together (MonoSLAMBOT Fig. 1): the
 * IMM SLAM filter (static world) and, when enabled, the shadow filter that holds new features until
 * they are classified. One role per class; this class only wires them and owns no maths. */
#pragma once

#include <immslam/camera/CCameraModel.h>
#include <immslam/slam/CMonoSlamIMM.h>

#include <mrpt/config/CConfigFileBase.h>
#include <mrpt/config/CLoadableOptions.h>
#include <opencv2/core/mat.hpp>

#include <map>
#include <memory>
#include <set>
#include <string>

namespace immslam::system
{
/** Result of one frame of the whole system. */
struct TSystemFrame
{
  const slam::TFrameReport* slam = nullptr;  ///< the SLAM filter's report (valid until the next frame)
  double totalMs = 0;                        ///< wall time of processFrame (image decoding excluded)
};

class CMonoSlamSystem
{
 public:
  /** Options of the wiring (section [system]). */
  struct TOptions : public mrpt::config::CLoadableOptions
  {
    /** Where new features go: into the SLAM filter directly (false) or first to the shadow filter. */
    bool shadow_filter = false;
    void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override;
    void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override;
  };

  /** Loads [system], [slam], [imm], [ransac] (and [shadow]) from cfg.
   * \throws std::runtime_error naming the section/key of a bad value. */
  CMonoSlamSystem(const mrpt::config::CConfigFileBase& cfg, camera::CCameraModel::Ptr cam);
  ~CMonoSlamSystem();

  /** Processes one 8-bit grey frame of the camera's size. */
  const TSystemFrame& processFrame(double timestamp, const cv::Mat& grey);

  const slam::CMonoSlamIMM& slam() const { return *m_slam; }
  slam::CMonoSlamIMM& slam() { return *m_slam; }
  const TOptions& options() const { return m_opts; }

  /** Writes every effective option of the system (all sections) into cfg. */
  void saveEffectiveConfig(mrpt::config::CConfigFileBase& cfg) const;
  /** Keys known per section (for the unknown-key check of the application). */
  static std::map<std::string, std::set<std::string>> knownKeys();

 private:
  TOptions m_opts;
  slam::CMonoSlamIMM::TOptions m_slamOpts;
  slam::TIMMBankOptions m_bankOpts;
  slam::COnePointRansac::TOptions m_ransacOpts;
  std::unique_ptr<slam::CMonoSlamIMM> m_slam;
  TSystemFrame m_frame;
};
}  // namespace immslam::system
