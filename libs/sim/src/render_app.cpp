/* imm-monoslam — imm-render (see render_app.h). */
#include <immslam/sim/CSimulator.h>
#include <immslam/sim/render_app.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
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
         "  --points N[,M]           also points_groundtruth.txt: point tracks with known association, N on the\n"
         "                           static world, M (default N/20, at least 4) on each moving object\n"
         "  --point-noise PX         Gaussian noise of the point tracks' projections (default 0.5 px)\n"
         "  --help                   this text\n"
         "Exit status: 0 success, 1 bad input or failure, 2 bad usage.\n";
}

namespace
{
/** The command line of imm-render. */
struct TRenderArgs
{
  std::vector<std::string> positional, overrides;
  long long frames = 0;
  std::string seedOverride;
  std::optional<TPointTrackOptions> points;
  double pointNoise = 0.5;
  bool help = false;
};

/** Parses the options of `args` into r; the usage error, or "" (r.help after --help). */
std::string parseRenderArgs(const std::vector<std::string>& args, TRenderArgs& r)
{
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
      r.help = true;
      return std::string();
    }
    else if (a.rfind("--frames", 0) == 0)
    {
      if (!value("--frames", v)) return "--frames needs a value";
      char* end = nullptr;
      r.frames = std::strtoll(v.c_str(), &end, 10);
      if (v.empty() || *end != '\0' || r.frames <= 0) return "--frames needs a positive integer, got '" + v + "'";
    }
    else if (a.rfind("--points", 0) == 0 && a.rfind("--point-noise", 0) != 0)
    {
      if (!value("--points", v)) return "--points needs a value";
      int nStatic = -1, nObject = -1;
      char tail = 0;
      const int got = std::sscanf(v.c_str(), "%d,%d%c", &nStatic, &nObject, &tail);
      if (!((got == 1 && v.find(',') == std::string::npos) || got == 2) || nStatic < 0 || (got == 2 && nObject < 0))
        return "--points needs N or N,M (counts >= 0), got '" + v + "'";
      r.points = TPointTrackOptions();
      r.points->staticPoints = nStatic;
      r.points->pointsPerObject = got == 2 ? nObject : std::max(4, nStatic / 20);
    }
    else if (a.rfind("--point-noise", 0) == 0)
    {
      if (!value("--point-noise", v)) return "--point-noise needs a value";
      char* end = nullptr;
      r.pointNoise = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !(r.pointNoise >= 0) || !std::isfinite(r.pointNoise))
        return "--point-noise needs a number >= 0 (px), got '" + v + "'";
    }
    else if (a.rfind("--seed", 0) == 0)
    {
      if (!value("--seed", v)) return "--seed needs a value";
      r.seedOverride = v;
    }
    else if (a.rfind("--set", 0) == 0)
    {
      if (!value("--set", v)) return "--set needs SECTION.KEY=VALUE";
      if (v.find('.') == std::string::npos || v.find('=') == std::string::npos || v.find('.') > v.find('='))
        return "--set needs SECTION.KEY=VALUE, got '" + v + "'";
      r.overrides.push_back(v);
    }
    else if (a.size() > 1 && a[0] == '-')
      return "unknown option '" + a + "'";
    else
      r.positional.push_back(a);
  }
  return std::string();
}

/** Renders the scenario r.positional[0] into r.positional[1] (and its point tracks).
 * \return 0, or 1 with the message on `err`. */
int render(const TRenderArgs& r, std::ostream& out, std::ostream& err)
{
  try
  {
    const CSimulator sim(TScenario::loadFile(r.positional[0], r.overrides));
    std::size_t n = sim.frameCount();
    if (r.frames > 0)
    {
      if (static_cast<std::size_t>(r.frames) > n)
        err << "imm-render: note: the scenario has only " << n << " frames (--frames " << r.frames << ")\n";
      else
        n = static_cast<std::size_t>(r.frames);
    }
    const TWriteStats s = sim.writeDataset(r.positional[1], n);

    const auto& cam = *sim.camera();
    out << "imm-render: wrote " << s.frames << " frames (" << cam.width() << "x" << cam.height() << " "
        << cam.modelName() << ", " << sim.world().movingObjects().size() << " moving objects) to " << r.positional[1]
        << "\n"
        << "imm-render: " << (s.renderSeconds > 0 ? s.frames / s.renderSeconds : 0.0) << " frames/s rendering, "
        << (s.totalSeconds > 0 ? s.frames / s.totalSeconds : 0.0) << " frames/s including PNG writing\n";
    if (r.points)
    {
      TPointTrackOptions points = *r.points;
      points.noisePx = r.pointNoise;
      const std::size_t rows = sim.writePointTracks(r.positional[1] + "/points_groundtruth.txt", n, points);
      out << "imm-render: wrote " << rows << " point measurements to " << r.positional[1] << "/points_groundtruth.txt\n";
    }
    return 0;
  }
  catch (const std::exception& e)
  {
    err << "imm-render: error: " << e.what() << "\n";
    return 1;
  }
}
}  // namespace

int runRenderApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  TRenderArgs r;
  const auto usageError = [&](const std::string& msg) {
    err << "imm-render: " << msg << "\n" << renderAppUsage();
    return 2;
  };
  if (const std::string e = parseRenderArgs(args, r); !e.empty()) return usageError(e);
  if (r.help)
  {
    out << renderAppUsage();
    return 0;
  }
  if (r.positional.size() != 2) return usageError("expected SCENARIO.ini and OUT_FOLDER");
  if (!r.seedOverride.empty()) r.overrides.push_back("scenario.seed=" + r.seedOverride);
  return render(r, out, err);
}
}  // namespace immslam::sim
