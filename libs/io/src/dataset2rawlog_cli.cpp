/* imm-monoslam — command line of the dataset2rawlog program. */
#include <immslam/io/dataset2rawlog.h>

#include <chrono>
#include <iomanip>
#include <ostream>

namespace immslam::io
{
namespace
{
void printUsage(std::ostream& o)
{
  o << "Usage: dataset2rawlog FOLDER OUT.rawlog [--embed] [--layout obs|sf] [--help]\n"
       "Converts a dataset folder (rgb.txt, calib.txt, groundtruth.txt) into an MRPT rawlog:\n"
       "CObservationImage (label CAMERA, calibration in cameraParams when MRPT's TCamera can hold it)\n"
       "and, with groundtruth.txt, CObservationRobotPose (label GT, T_world_camera), by timestamp.\n"
       "  --embed          store the pixels in the rawlog (default: reference the image files by a\n"
       "                   path relative to the rawlog's folder)\n"
       "  --layout obs|sf  plain observations (default) or action/sensory-frame pairs\n"
       "  --help           this text\n"
       "Exit status: 0 success, 1 failure, 2 bad usage.\n";
}
}  // namespace

int dataset2rawlogCli(const std::vector<std::string>& args, std::ostream& out, std::ostream& err)
{
  std::vector<std::string> positional;
  TDataset2RawlogOptions opts;
  for (std::size_t i = 0; i < args.size(); ++i)
  {
    const std::string& a = args[i];
    if (a == "--help" || a == "-h")
    {
      printUsage(out);
      return 0;
    }
    if (a == "--embed")
      opts.embedImages = true;
    else if (a == "--layout" || a.rfind("--layout=", 0) == 0)
    {
      std::string v;
      if (a == "--layout")
      {
        if (i + 1 >= args.size())
        {
          err << "dataset2rawlog: --layout needs a value (obs or sf)\n";
          printUsage(err);
          return 2;
        }
        v = args[++i];
      }
      else
        v = a.substr(9);
      if (v == "obs")
        opts.layout = ERawlogLayout::Observations;
      else if (v == "sf")
        opts.layout = ERawlogLayout::SensoryFrames;
      else
      {
        err << "dataset2rawlog: unknown --layout '" << v << "' (expected obs or sf)\n";
        return 2;
      }
    }
    else if (a.size() > 1 && a[0] == '-')
    {
      err << "dataset2rawlog: unknown option '" << a << "'\n";
      printUsage(err);
      return 2;
    }
    else
      positional.push_back(a);
  }
  if (positional.size() != 2)
  {
    err << "dataset2rawlog: expected FOLDER and OUT.rawlog\n";
    printUsage(err);
    return 2;
  }

  try
  {
    const auto t0 = std::chrono::steady_clock::now();
    const TDataset2RawlogResult r = convertDatasetToRawlog(positional[0], positional[1], opts);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (const auto& w : r.warnings) err << "dataset2rawlog: warning: " << w << "\n";
    out << "dataset2rawlog: wrote " << positional[1] << ": " << r.nImages << " images ("
        << (opts.embedImages ? "embedded" : "external") << "), " << r.nGroundTruth
        << " ground-truth poses, " << r.nSkipped << " entries skipped, "
        << (opts.layout == ERawlogLayout::SensoryFrames ? "action/sensory-frame pairs"
                                                        : "plain observations")
        << ", calibration " << (r.calibrationStored ? "stored" : "NOT stored") << " ("
        << std::fixed << std::setprecision(2) << secs << " s)\n";
    return 0;
  }
  catch (const std::exception& e)
  {
    err << "dataset2rawlog: error: " << e.what() << "\n";
    return 1;
  }
}
}  // namespace immslam::io
