/* Fuzz target: ini option loading (core strict readers, syntax and key checks, every options class,
 * the [camera] section and the renderer's scenarios) through mrpt::config::CConfigFileMemory. */
#include "fuzz_common.h"

#include <immslam/camera/mrpt_camera.h>
#include <immslam/core/config.h>
#include <immslam/shadow/CShadowFilter.h>
#include <immslam/sim/TScenario.h>
#include <immslam/tracking/CMonoSlamIMM.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <mrpt/config/CConfigFileMemory.h>

#include <cmath>

namespace immslam::fuzz
{
namespace
{
/** Runs f; an exception must name `name` (the section). */
template <typename F>
void expectClean(const std::string& name, const char* what, F&& f)
{
  try
  {
    f();
  }
  catch (const std::exception& e)
  {
    requireMentions(e, name, what);
  }
}
}  // namespace

int fuzzIni(const std::uint8_t* data, std::size_t size)
{
  const std::string text(reinterpret_cast<const char*>(data), size);
  try
  {
    core::checkIniSyntax(text, "fuzz.ini");
  }
  catch (const std::exception& e)
  {
    requireMentions(e, "fuzz.ini:", "checkIniSyntax");
  }
  mrpt::config::CConfigFileMemory cfg;
  try
  {
    cfg.setContent(text);
  }
  catch (const std::exception&)
  {
    return 0;  // MRPT's own parser (preprocessor errors): not ours
  }
  std::vector<std::string> sections;
  cfg.getAllSections(sections);
  auto known = system::CMonoSlamSystem::knownKeys();
  for (const auto& s : sections)
  {
    std::vector<std::string> keys;
    cfg.getAllKeys(s, keys);
    for (const auto& k : keys)
    {
      const std::string tag = "[" + s + "]";
      expectClean(tag, "readDouble", [&] {
        const double v = core::readDouble(cfg, s, k, 0.0);
        if (std::isnan(v)) fail("readDouble returned NaN");
      });
      expectClean(tag, "readInt", [&] { core::readInt(cfg, s, k, 0); });
      expectClean(tag, "readBool", [&] { core::readBool(cfg, s, k, false); });
      expectClean(tag, "readVector", [&] {
        for (const double v : core::readVector(cfg, s, k, {}))
          if (std::isnan(v)) fail("readVector returned NaN");
      });
      (void)core::readString(cfg, s, k, "");
    }
    if (const auto it = known.find(s); it != known.end())
      expectClean("[" + s + "]", "checkKnownKeys", [&] { core::checkKnownKeys(cfg, s, it->second); });
  }
  // Every options class of the system: loading validates (errors name the section).
  expectClean("[system]", "system options", [&] { system::CMonoSlamSystem::TOptions().loadFromConfigFile(cfg, "system"); });
  expectClean("[search]", "search options", [&] { system::CMonoSlamSystem::TSearchOptions().loadFromConfigFile(cfg, "search"); });
  expectClean("[slam]", "slam options", [&] { slam::CMonoSlamIMM::TOptions().loadFromConfigFile(cfg, "slam"); });
  expectClean("[ransac]", "ransac options", [&] { slam::COnePointRansac::TOptions().loadFromConfigFile(cfg, "ransac"); });
  expectClean("[shadow]", "shadow options", [&] { shadow::CShadowFilter::TOptions().loadFromConfigFile(cfg, "shadow"); });
  expectClean("[imm]", "imm options", [&] {
    slam::TIMMBankOptions o;
    o.loadFromConfigFile(cfg, "imm");
    const int r = static_cast<int>(o.parseModels().size());
    const MatX pi = o.transitionMatrix(r);
    const VecX prior = o.priorProbabilities(r);
    if (!pi.allFinite() || !prior.allFinite() || std::abs(prior.sum() - 1) > 1e-6)
      fail("[imm]: accepted a transition matrix or prior that is not finite / does not sum to 1");
  });
  expectClean("[camera]", "camera section", [&] {
    if (cfg.sectionExists("camera")) (void)camera::loadCameraFromConfig(cfg, "camera");
  });
  expectClean("fuzz-scenario", "scenario", [&] { (void)sim::TScenario::fromConfig(cfg, "fuzz-scenario"); });
  return 0;
}
}  // namespace immslam::fuzz
