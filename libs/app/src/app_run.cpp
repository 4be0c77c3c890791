/* imm-monoslam — CImmMonoSlamApp::run(): resolve the inputs, settle the camera at the first frame,
 * build the system once, build the writers, run the frame loop (which publishes every frame to the
 * writers and tells them the end), print the summary. The steps live in this folder: run_inputs.h
 * (inputs), settle_camera.h (the camera), CFrameLoop.h (frames), CRunOutputs.h (writers). */
#include <immslam/app/CImmMonoSlamApp.h>

#include "CFrameLoop.h"
#include "CRunOutputs.h"
#include "run_inputs.h"
#include "settle_camera.h"

#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

namespace immslam::app
{
namespace
{
/** The effective configuration, saved with every run (config_effective.ini) and printed unless --quiet. */
void writeEffectiveConfig(const detail::TRunContext& ctx, const detail::TRunInputs& in, const COutputFiles& out,
                          const std::string& effective, const std::string& version)
{
  std::ofstream f(out.path("config_effective.ini"));
  f << "# Effective configuration of this run (" << version << ")\n# config: " << ctx.args.config << "\n# camera: "
    << in.calibAsGiven << "\n"
    << effective;
  if (!ctx.args.quiet) ctx.log.logStr(mrpt::system::LVL_DEBUG, "effective configuration:\n" + effective);
}

/** The summary line printed at the end of a run. */
std::string summaryLine(const TRunSummary& sum, const std::string& outDir)
{
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << "frames " << sum.framesProcessed << " processed";
  if (sum.framesSkipped) s << ", " << sum.framesSkipped << " skipped";
  if (sum.framesWithoutMask) s << ", " << sum.framesWithoutMask << " without exclusion mask";
  if (sum.framesWithoutTracks) s << ", " << sum.framesWithoutTracks << " without known-association tracks";
  s << "; " << sum.fps << " fps (median " << std::setprecision(2) << sum.medianFrameMs << " ms/frame)"
    << "; map " << sum.finalMapSize << " features; median matched " << std::setprecision(0) << sum.medianMatched;
  if (sum.ate)
  {
    s << std::setprecision(4) << "; ATE (Sim3) " << sum.ate->rmse;
    if (sum.ate->pathLength > 0)
      s << " = " << std::setprecision(2) << 100 * sum.ate->rmseOverPath << " % of path, "
        << 100 * sum.ate->rmseOverExtent << " % of extent";
    else
      s << " (the ground-truth camera did not move)";
    s << " (" << sum.ate->nPairs << " poses)";
  }
  if (sum.ateRefined && sum.ateRefined->pathLength > 0)
    s << std::setprecision(2) << "; refined " << 100 * sum.ateRefined->rmseOverPath << " % of path";
  if (sum.ateSmoothed && sum.ateSmoothed->pathLength > 0)
    s << std::setprecision(2) << "; smoothed " << 100 * sum.ateSmoothed->rmseOverPath << " % of path";
  if (!sum.endReason.empty()) s << "; ended: " << sum.endReason;
  s << "; outputs in " << outDir;
  return s.str();
}

/** The exit status of a finished run: 1 (with a message) when no frame was usable or the input ended
 * on damage (every output up to it is written), else 0. */
int exitStatus(const TRunSummary& sum, const io::CImageSource& source, const std::string& outDir)
{
  if (sum.framesProcessed == 0)
  {
    std::cerr << "imm-monoslam: error: no usable frame in the input (" << sum.framesRead << " read, "
              << sum.framesSkipped << " skipped"
              << (sum.skipReasons.empty() ? std::string() : "; first: " + sum.skipReasons[0]) << ")\n";
    return 1;
  }
  if (source.endedOnDamage())
  {
    // Every output up to the damage is written (above); the damage itself is an error of the input.
    std::cerr << "imm-monoslam: error: " << sum.endReason << " (outputs up to it written to " << outDir << ")\n";
    return 1;
  }
  return 0;
}

/** The system of a run, built once for the settled camera.
 * \throws std::runtime_error prefixed by the config file for a bad [system], [slam], [shadow]... section. */
std::unique_ptr<system::CMonoSlamSystem> buildSystem(const detail::TRunContext& ctx, const detail::TRunInputs& in)
{
  try
  {
    auto sys = std::make_unique<system::CMonoSlamSystem>(ctx.cfg, in.cam);
    sys->slam().setRelativePoseLag(in.out.relative_pose_lag);
    return sys;
  }
  catch (const std::exception& e)
  {
    throw std::runtime_error(ctx.args.config + ": " + e.what());
  }
}

/** Clears the live source published to requestStop(), on every way out of a run. */
struct TLiveGuard
{
  std::atomic<io::CLiveCameraSource*>& p;
  ~TLiveGuard() { p = nullptr; }
};
}  // namespace

int CImmMonoSlamApp::run()
{
  try
  {
    return runImpl();
  }
  catch (const std::exception& e)
  {
    std::cerr << "imm-monoslam: error: " << e.what() << "\n";
    return 1;
  }
}

int CImmMonoSlamApp::runImpl()
{
  m_summary = TRunSummary();
  m_summary.outDir = m_args.outDir;
  const detail::TRunContext ctx{m_args, m_cfg, m_configDir, *this};
  detail::TRunInputs in;
  // The live source is published to requestStop() while it exists: the guard, declared after the
  // inputs that own the source, clears it before the source is destroyed.
  const TLiveGuard liveGuard{m_live};
  detail::resolveInputs(ctx, in, m_live, m_stop);

  detail::TSettledInput settled = detail::settleCamera(ctx, in, m_summary, m_stop);
  const std::unique_ptr<system::CMonoSlamSystem> sys = buildSystem(ctx, in);
  detail::CRunOutputs outputs(ctx, in, *sys, m_summary, settled.calibrationGuessed);
  writeEffectiveConfig(ctx, in, outputs.files(), effectiveConfigText(), version());

  detail::CFrameLoop loop(ctx, in, *sys, settled.reduction, m_summary);
  loop.run(std::move(settled.first), outputs.sinks(), m_stop);
  std::cout << summaryLine(m_summary, m_args.outDir) << std::endl;
  return exitStatus(m_summary, *in.source, m_args.outDir);
}
}  // namespace immslam::app
