/* imm-monoslam — renderer as an image source (see CSyntheticSource.h). */
#include <immslam/sim/CSyntheticSource.h>

#include <stdexcept>

namespace immslam::sim
{
CSyntheticSource::CSyntheticSource(std::shared_ptr<const CSimulator> sim, std::size_t maxFrames) : m_sim(std::move(sim))
{
  if (!m_sim) throw std::runtime_error("CSyntheticSource: null simulator");
  m_count = m_sim->frameCount();
  if (maxFrames > 0 && maxFrames < m_count) m_count = maxFrames;
}

CSyntheticSource::CSyntheticSource(TScenario scenario, std::size_t maxFrames)
    : CSyntheticSource(std::make_shared<const CSimulator>(std::move(scenario)), maxFrames)
{
}

CSyntheticSource::CSyntheticSource(const std::string& scenarioPath, const std::vector<std::string>& overrides,
                                   std::size_t maxFrames)
    : CSyntheticSource(std::make_shared<const CSimulator>(TScenario::loadFile(scenarioPath, overrides)), maxFrames)
{
}

io::ENextStatus CSyntheticSource::next(io::TFrame& frame, std::string& why)
{
  why.clear();
  if (m_next >= m_count) return io::ENextStatus::End;
  TSyntheticFrame f = m_sim->render(m_next);
  frame = io::TFrame();
  frame.timestamp = f.timestamp;
  frame.index = m_next;
  frame.grey = f.grey;
  frame.colour = f.colour;
  frame.camera = m_sim->camera();
  frame.origin = "synthetic frame " + std::to_string(m_next);
  m_lastIndex = m_next;
  m_lastMask = f.mask;
  ++m_next;
  return io::ENextStatus::Frame;
}

std::string CSyntheticSource::describe() const
{
  const auto& sc = m_sim->scenario();
  return "synthetic scenario " + sc.origin + " (seed " + std::to_string(sc.seed) + ", " + std::to_string(m_count) +
         " frames, " + std::to_string(m_sim->world().movingObjects().size()) + " moving objects)";
}

cv::Mat CSyntheticSource::mask(std::size_t k) const
{
  if (k == m_lastIndex) return m_lastMask;
  return m_sim->renderMask(k);
}
}  // namespace immslam::sim
