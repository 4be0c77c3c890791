/* imm-monoslam — main program: a thin wrapper around immslam::app::CImmMonoSlamApp. */
#include <immslam/app/CImmMonoSlamApp.h>
#include <immslam/refine/bundle_adjust.h>

#include <csignal>

namespace
{
immslam::app::CImmMonoSlamApp* g_app = nullptr;  // for the Ctrl-C handler only
extern "C" void onSigint(int)
{
  if (g_app) g_app->requestStop();
}
}  // namespace

int main(int argc, char** argv)
{
  immslam::refine::quietSolverLog();  // the smoother's Ceres solves
  immslam::app::CImmMonoSlamApp app;
  const int st = app.initialize(argc, argv);
  if (st >= 0) return st;
  g_app = &app;
  std::signal(SIGINT, onSigint);
  const int rc = app.run();
  std::signal(SIGINT, SIG_DFL);  // the handler must not outlive `app`
  g_app = nullptr;
  return rc;
}
