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
  std::vector<std::string> positional;
  auto needValue = [&](std::size_t& i, const std::string& opt, std::string& out) -> bool {
    if (i + 1 >= args.size())
    {
      std::cerr << "imm-monoslam: option " << opt << " needs a value\n" << usage();
      return false;
    }
    out = args[++i];
    return true;
  };
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    std::string v;
    if (a == "--help" || a == "-h")
    {
      std::cout << usage();
      return 0;
    }
    if (a == "--version")
    {
      std::cout << version() << "\n";
      return 0;
    }
    if (a == "--out")
    {
      if (!needValue(i, a, m_args.outDir)) return 2;
    }
    else if (a == "--calib")
    {
      if (!needValue(i, a, m_args.calib)) return 2;
    }
    else if (a == "--fov")
    {
      if (!needValue(i, a, v)) return 2;
      try
      {
        std::size_t pos = 0;
        m_args.fovDeg = std::stod(v, &pos);
        if (pos != v.size() || !(m_args.fovDeg >= 1 && m_args.fovDeg <= 179)) throw std::invalid_argument(v);
      }
      catch (const std::exception&)
      {
        std::cerr << "imm-monoslam: --fov needs a horizontal field of view in degrees in [1, 179], got '" << v
                  << "'\n";
        return 2;
      }
    }
    else if (a == "--live")
    {
      if (!needValue(i, a, m_args.live)) return 2;
    }
    else if (a == "--record")
    {
      if (!needValue(i, a, m_args.record)) return 2;
    }
    else if (a == "--frames")
    {
      if (!needValue(i, a, v)) return 2;
      try
      {
        std::size_t pos = 0;
        m_args.maxFrames = std::stoll(v, &pos);
        if (pos != v.size() || m_args.maxFrames < 0) throw std::invalid_argument(v);
      }
      catch (const std::exception&)
      {
        std::cerr << "imm-monoslam: --frames needs a non-negative integer, got '" << v << "'\n";
        return 2;
      }
    }
    else if (a == "--set")
    {
      if (!needValue(i, a, v)) return 2;
      m_args.sets.push_back(v);
    }
    else if (a == "--no-gui")
      m_args.noGui = true;
    else if (a == "--quiet")
      m_args.quiet = true;
    else if (a == "--print-config")
      m_args.printConfig = true;
    else if (a.size() > 1 && a[0] == '-')
    {
      std::cerr << "imm-monoslam: unknown option '" << a << "'\n" << usage();
      return 2;
    }
    else
      positional.push_back(a);
  }
  if (positional.empty() || positional.size() > 2)
  {
    std::cerr << "imm-monoslam: expected CONFIG.ini [INPUT]\n" << usage();
    return 2;
  }
  m_args.config = positional[0];
  if (positional.size() == 2) m_args.input = positional[1];
  if (!m_args.input.empty() && !m_args.live.empty())
  {
    std::cerr << "imm-monoslam: give either INPUT or --live, not both\n";
    return 2;
  }
  if (!m_args.calib.empty() && m_args.fovDeg > 0)
  {
    std::cerr << "imm-monoslam: give either --calib or --fov (a guess for an input without calibration), not both\n";
    return 2;
  }

  // Configuration: the file, then the --set overrides (in order).
  if (!fs::is_regular_file(m_args.config))
  {
    std::cerr << "imm-monoslam: cannot read config file '" << m_args.config << "'\n";
    return 1;
  }
  {
    std::ifstream f(m_args.config);
    std::stringstream ss;
    ss << f.rdbuf();
    // MRPT's parser silently drops lines it cannot read (no '=', keys before any [section], junk):
    // a mistyped line would leave its key at the default. Refuse them, naming file and line.
    try
    {
      core::checkIniSyntax(ss.str(), m_args.config);
    }
    catch (const std::exception& e)
    {
      std::cerr << "imm-monoslam: error: " << e.what() << "\n";
      return 1;
    }
    m_cfg.setContent(ss.str());
  }
  m_configDir = fs::path(m_args.config).parent_path().string();
  for (const auto& s : m_args.sets)
  {
    const auto dot = s.find('.'), eq = s.find('=');
    if (dot == std::string::npos || eq == std::string::npos || dot > eq || dot == 0 || eq == dot + 1)
    {
      std::cerr << "imm-monoslam: --set needs SECTION.KEY=VALUE, got '" << s << "'\n";
      return 2;
    }
    m_cfg.write(s.substr(0, dot), s.substr(dot + 1, eq - dot - 1), s.substr(eq + 1));
  }
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
