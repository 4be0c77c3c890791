/* imm-monoslam — imm-render (see render_app.h). */
#include <immslam/sim/CSimulator.h>
#include <immslam/sim/render_app.h>

#include <cstdlib>
#include <exception>
#include <ostream>

namespace immslam::sim
{
std::string renderAppUsage()
{
  return "Usage: imm-render SCENARIO.ini OUT_FOLDER [options]\n"
         "Renders a synthetic image sequence with ground truth (ini/scenarios/*.ini) into a dataset folder:\n"
         "  rgb/ rgb.txt calib.txt groundtruth.txt (T_W_C), motion_labels.txt, camera_velocity.txt,\n"
         "  objects_groundtruth.txt (T_W_O), masks/ (0 static world, k moving object k), world_boxes.txt,\n"
         "  scenario.ini (the effective scenario).\n"
         "Options:\n"
         "  --frames N               write only the first N frames\n"
         "  --seed S                 override [scenario] seed\n"
         "  --set SECTION.KEY=VALUE  override one scenario key (repeatable)\n"
         "  --help                   this text\n"
         "Exit status: 0 success, 1 bad input or failure, 2 bad usage.\n";
}

int runRenderApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  std::vector<std::string> positional, overrides;
  long long frames = 0;
  std::string seedOverride;
  const auto usageError = [&](const std::string& msg) {
    err << "imm-render: " << msg << "\n" << renderAppUsage();
    return 2;
  };
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    const auto value = [&](const std::string& name, std::string& v) {
      if (a.rfind(name + "=", 0) == 0)
      {
        v = a.substr(name.size() + 1);
        return true;
      }
      if (a == name && i + 1 < args.size())
      {
        v = args[++i];
        return true;
      }
      return false;
    };
    std::string v;
    if (a == "--help" || a == "-h")
    {
      out << renderAppUsage();
      return 0;
    }
    else if (a.rfind("--frames", 0) == 0)
    {
      if (!value("--frames", v)) return usageError("--frames needs a value");
      char* end = nullptr;
      frames = std::strtoll(v.c_str(), &end, 10);
      if (v.empty() || *end != '\0' || frames <= 0) return usageError("--frames needs a positive integer, got '" + v + "'");
    }
    else if (a.rfind("--seed", 0) == 0)
    {
      if (!value("--seed", v)) return usageError("--seed needs a value");
      seedOverride = v;
    }
    else if (a.rfind("--set", 0) == 0)
    {
      if (!value("--set", v)) return usageError("--set needs SECTION.KEY=VALUE");
      if (v.find('.') == std::string::npos || v.find('=') == std::string::npos || v.find('.') > v.find('='))
        return usageError("--set needs SECTION.KEY=VALUE, got '" + v + "'");
      overrides.push_back(v);
    }
    else if (a.size() > 1 && a[0] == '-')
      return usageError("unknown option '" + a + "'");
    else
      positional.push_back(a);
  }
  if (positional.size() != 2) return usageError("expected SCENARIO.ini and OUT_FOLDER");
  if (!seedOverride.empty()) overrides.push_back("scenario.seed=" + seedOverride);

  try
  {
    const CSimulator sim(TScenario::loadFile(positional[0], overrides));
    std::size_t n = sim.frameCount();
    if (frames > 0)
    {
      if (static_cast<std::size_t>(frames) > n)
        err << "imm-render: note: the scenario has only " << n << " frames (--frames " << frames << ")\n";
      else
        n = static_cast<std::size_t>(frames);
    }
    const TWriteStats s = sim.writeDataset(positional[1], n);
    const auto& cam = *sim.camera();
    out << "imm-render: wrote " << s.frames << " frames (" << cam.width() << "x" << cam.height() << " "
        << cam.modelName() << ", " << sim.world().movingObjects().size() << " moving objects) to " << positional[1]
        << "\n"
        << "imm-render: " << (s.renderSeconds > 0 ? s.frames / s.renderSeconds : 0.0) << " frames/s rendering, "
        << (s.totalSeconds > 0 ? s.frames / s.totalSeconds : 0.0) << " frames/s including PNG writing\n";
    return 0;
  }
  catch (const std::exception& e)
  {
    err << "imm-render: error: " << e.what() << "\n";
    return 1;
  }
}
}  // namespace immslam::sim
