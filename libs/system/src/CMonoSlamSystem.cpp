/* imm-monoslam — wiring of the SLAM filter (and the shadow filter) per frame. */
#include <immslam/core/config.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <chrono>

namespace immslam::system
{
void CMonoSlamSystem::TOptions::loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s)
{
  IMMSLAM_LOAD_BOOL(shadow_filter);
}

void CMonoSlamSystem::TOptions::saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const
{
  MRPT_SAVE_CONFIG_VAR_COMMENT(shadow_filter, "new features go first to the MonoSLAMBOT shadow filter");
}

CMonoSlamSystem::CMonoSlamSystem(const mrpt::config::CConfigFileBase& cfg, camera::CCameraModel::Ptr cam)
{
  m_opts.loadFromConfigFile(cfg, "system");
  m_slamOpts.loadFromConfigFile(cfg, "slam");
  m_bankOpts.loadFromConfigFile(cfg, "imm");
  m_ransacOpts.loadFromConfigFile(cfg, "ransac");
  if (m_opts.shadow_filter)
    throw std::runtime_error("[system] shadow_filter = true: the shadow filter is not available in this build yet");
  m_slam = std::make_unique<slam::CMonoSlamIMM>(m_slamOpts, m_bankOpts, m_ransacOpts, std::move(cam));
}

CMonoSlamSystem::~CMonoSlamSystem() = default;

const TSystemFrame& CMonoSlamSystem::processFrame(double timestamp, const cv::Mat& grey)
{
  const auto t0 = std::chrono::steady_clock::now();
  m_frame.slam = &m_slam->processFrame(timestamp, grey);
  // Map management: new features where the image is empty of tracked ones.
  if (m_frame.slam->frame > 0)
  {
    const int want = m_slam->wantedNewFeatures();
    if (want > 0)
    {
      std::vector<Vec2> uv;
      for (const auto& c : m_slam->findNewFeatureCandidates(grey, want)) uv.push_back(c.uv);
      m_slam->addFeaturesAt(grey, uv);
    }
  }
  m_frame.totalMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return m_frame;
}

void CMonoSlamSystem::saveEffectiveConfig(mrpt::config::CConfigFileBase& cfg) const
{
  m_opts.saveToConfigFile(cfg, "system");
  m_slamOpts.saveToConfigFile(cfg, "slam");
  m_bankOpts.saveToConfigFile(cfg, "imm");
  m_ransacOpts.saveToConfigFile(cfg, "ransac");
}

std::map<std::string, std::set<std::string>> CMonoSlamSystem::knownKeys()
{
  return {{"system", core::knownKeys(TOptions(), "system")},
          {"slam", core::knownKeys(slam::CMonoSlamIMM::TOptions(), "slam")},
          {"imm", core::knownKeys(slam::TIMMBankOptions(), "imm")},
          {"ransac", core::knownKeys(slam::COnePointRansac::TOptions(), "ransac")}};
}
}  // namespace immslam::system
