/* imm-monoslam — command line and configuration of the main application. */
#include <immslam/app/CImmMonoSlamApp.h>

#include <immslam/app/app_options.h>
#include <immslam/core/config.h>
#include <immslam/io/CLiveCameraSource.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <mrpt/config/CConfigFile.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#ifndef IMMSLAM_VERSION
#define IMMSLAM_VERSION "unknown"
#endif

namespace immslam::app
{
namespace fs = std::filesystem;

namespace
{
/** The value of option args[i] into `out` (i advanced); false (usage printed) when it has none. */
bool needValue(const std::vector<std::string>& args, std::size_t& i, std::string& out)
{
  if (i + 1 >= args.size())
  {
    std::cerr << "imm-monoslam: option " << args[i] << " needs a value\n" << CImmMonoSlamApp::usage();
    return false;
  }
  out = args[++i];
  return true;
}

/** --fov DEG: a horizontal field of view in [1, 179] degrees; false (message printed) otherwise. */
bool parseFov(const std::string& v, double& fovDeg)
{
  try
  {
    std::size_t pos = 0;
    fovDeg = std::stod(v, &pos);
    if (pos != v.size() || !(fovDeg >= 1 && fovDeg <= 179)) throw std::invalid_argument(v);
    return true;
  }
  catch (const std::exception&)
  {
    std::cerr << "imm-monoslam: --fov needs a horizontal field of view in degrees in [1, 179], got '" << v << "'\n";
    return false;
  }
}

/** --frames N: a non-negative integer; false (message printed) otherwise. */
bool parseFrames(const std::string& v, long long& maxFrames)
{
  try
  {
    std::size_t pos = 0;
    maxFrames = std::stoll(v, &pos);
    if (pos != v.size() || maxFrames < 0) throw std::invalid_argument(v);
    return true;
  }
  catch (const std::exception&)
  {
    std::cerr << "imm-monoslam: --frames needs a non-negative integer, got '" << v << "'\n";
    return false;
  }
}

/** One option at args[i] (its value read, i advanced). \return -1 to go on, 0 after --help or
 * --version, 2 on bad usage (message printed); `positional` gets an argument that is no option. */
int parseOption(const std::vector<std::string>& args, std::size_t& i, TAppArguments& out,
                std::vector<std::string>& positional)
{
  const std::string& a = args[i];
  std::string v;
  if (a == "--help" || a == "-h")
  {
    std::cout << CImmMonoSlamApp::usage();
    return 0;
  }
  if (a == "--version")
  {
    std::cout << CImmMonoSlamApp::version() << "\n";
    return 0;
  }
  // Options with a string value, read as they are.
  for (auto [name, field] : {std::pair{"--out", &out.outDir}, std::pair{"--calib", &out.calib},
                             std::pair{"--live", &out.live}, std::pair{"--record", &out.record}})
    if (a == name) return needValue(args, i, *field) ? -1 : 2;
  if (a == "--fov") return needValue(args, i, v) && parseFov(v, out.fovDeg) ? -1 : 2;
  if (a == "--frames") return needValue(args, i, v) && parseFrames(v, out.maxFrames) ? -1 : 2;
  if (a == "--set")
  {
    if (!needValue(args, i, v)) return 2;
    out.sets.push_back(v);
  }
  else if (a == "--no-gui")
    out.noGui = true;
  else if (a == "--quiet")
    out.quiet = true;
  else if (a == "--print-config")
    out.printConfig = true;
  else if (a.size() > 1 && a[0] == '-')
  {
    std::cerr << "imm-monoslam: unknown option '" << a << "'\n" << CImmMonoSlamApp::usage();
    return 2;
  }
  else
    positional.push_back(a);
  return -1;
}

/** The command line into `out`. \return -1 to go on, else the exit status (0 after --help or
 * --version, 2 on bad usage, message printed). */
int parseArguments(const std::vector<std::string>& args, TAppArguments& out)
{
  std::vector<std::string> positional;
  for (std::size_t i = 0; i < args.size(); ++i)
    if (const int status = parseOption(args, i, out, positional); status >= 0) return status;
  if (positional.empty() || positional.size() > 2)
  {
    std::cerr << "imm-monoslam: expected CONFIG.ini [INPUT]\n" << CImmMonoSlamApp::usage();
    return 2;
  }
  out.config = positional[0];
  if (positional.size() == 2) out.input = positional[1];
  if (!out.input.empty() && !out.live.empty())
  {
    std::cerr << "imm-monoslam: give either INPUT or --live, not both\n";
    return 2;
  }
  if (!out.calib.empty() && out.fovDeg > 0)
  {
    std::cerr << "imm-monoslam: give either --calib or --fov (a guess for an input without calibration), not both\n";
    return 2;
  }
  return -1;
}

/** The configuration: the file, then the --set overrides (in order). \return -1 to go on, else the
 * exit status (1: unreadable or malformed file, 2: a malformed --set; message printed). */
int loadConfig(const TAppArguments& args, mrpt::config::CConfigFileMemory& cfg)
{
  if (!fs::is_regular_file(args.config))
  {
    std::cerr << "imm-monoslam: cannot read config file '" << args.config << "'\n";
    return 1;
  }
  std::ifstream f(args.config);
  std::stringstream ss;
  ss << f.rdbuf();
  // MRPT's parser silently drops lines it cannot read (no '=', keys before any [section], junk):
  // a mistyped line would leave its key at the default. Refuse them, naming file and line.
  try
  {
    core::checkIniSyntax(ss.str(), args.config);
  }
  catch (const std::exception& e)
  {
    std::cerr << "imm-monoslam: error: " << e.what() << "\n";
    return 1;
  }
  cfg.setContent(ss.str());
  for (const auto& s : args.sets)
  {
    const auto dot = s.find('.'), eq = s.find('=');
    if (dot == std::string::npos || eq == std::string::npos || dot > eq || dot == 0 || eq == dot + 1)
    {
      std::cerr << "imm-monoslam: --set needs SECTION.KEY=VALUE, got '" << s << "'\n";
      return 2;
    }
    cfg.write(s.substr(0, dot), s.substr(dot + 1, eq - dot - 1), s.substr(eq + 1));
  }
  return -1;
}
}  // namespace

CImmMonoSlamApp::CImmMonoSlamApp() : mrpt::system::COutputLogger("imm-monoslam") {}
CImmMonoSlamApp::~CImmMonoSlamApp() = default;

std::string CImmMonoSlamApp::version() { return std::string("imm-monoslam ") + IMMSLAM_VERSION; }

std::string CImmMonoSlamApp::usage()
{
  return "Usage: imm-monoslam CONFIG.ini [INPUT] [options]\n"
         "  IMM monocular EKF SLAM (+ MonoSLAMBOT shadow filter) on a rawlog, a dataset folder,\n"
         "  a video file, a live MRPT camera, or the built-in rendered scene.\n"
         "  INPUT                   a .rawlog file, a dataset folder (rgb.txt, calib.txt, ...) or a\n"
         "                          video file (.mp4 .avi .mkv .mov ...; needs --calib or --fov);\n"
         "                          default: [input] source of the config\n"
         "Options:\n"
         "  --out DIR               output folder (default imm-monoslam-out)\n"
         "  --calib FILE            camera calibration (calib.txt format), overrides input/config\n"
         "  --fov DEG               no calibration at all: guess a pinhole camera of this horizontal\n"
         "                          field of view (centred, no distortion; written to calib_guessed.txt)\n"
         "  --live GRABBER.ini[:SECTION]  live capture through mrpt::hwdrivers::CCameraSensor\n"
         "  --record FILE.rawlog    record the live stream while running\n"
         "  --frames N              stop after N frames\n"
         "  --set SECTION.KEY=VALUE override one config key (repeatable)\n"
         "  --no-gui                never open a window\n"
         "  --quiet                 no progress line\n"
         "  --print-config          print the effective configuration (every key, with comments) and exit\n"
         "  --help, --version\n"
         "Exit status: 0 success, 1 bad input or failure, 2 bad usage.\n";
}

void CImmMonoSlamApp::requestStop()
{
  m_stop = true;
  if (io::CLiveCameraSource* live = m_live.load()) live->requestStop();
}

std::string CImmMonoSlamApp::effectiveConfigText() const
{
  mrpt::config::CConfigFileMemory eff;
  TInputOptions in;
  TOutputOptions out;
  in.loadFromConfigFile(m_cfg, "input");
  out.loadFromConfigFile(m_cfg, "output");
  in.saveToConfigFile(eff, "input");
  out.saveToConfigFile(eff, "output");
  system::CMonoSlamSystem::effectiveConfig(m_cfg, eff);
  return eff.getContent();
}

int CImmMonoSlamApp::initialize(int argc, const char* const* argv)
{
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
  return initialize(args);
}

int CImmMonoSlamApp::initialize(const std::vector<std::string>& args)
{
  if (const int status = parseArguments(args, m_args); status >= 0) return status;
  if (const int status = loadConfig(m_args, m_cfg); status >= 0) return status;
  m_configDir = fs::path(m_args.config).parent_path().string();
  if (m_args.printConfig)
  {
    try
    {
      std::cout << effectiveConfigText();
    }
    catch (const std::exception& e)
    {
      std::cerr << "imm-monoslam: " << m_args.config << ": " << e.what() << "\n";
      return 1;
    }
    return 0;
  }
  return -1;
}
}  // namespace immslam::app
