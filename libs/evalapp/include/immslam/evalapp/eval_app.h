/* imm-monoslam — the ATE report of slam-eval (`slam-eval ate`, formerly the imm-eval program). */
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::evalapp
{
/** Runs `PROG EST.txt GT.txt [--sim3|--se3|--no-align] [--max-dt S] [--rpe DELTA [--rpe-csv F]] [--json]`:
 * reads two TUM trajectories, computes the ATE (computeAte) and prints it as text or JSON to out.
 * This is `slam-eval ate` (runSlamEvalApp(), slam_eval_app.h, calls it with PROG = "slam-eval ate").
 * \param args the command line, args[0] being the program name.
 * \param out  report (and --help text).
 * \param err  error messages.
 * \return exit status: 0 success, 1 bad input (unreadable/malformed file, named in the message,
 *         or no associated poses), 2 bad usage. Never exits the process. */
int runEvalApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/** The --help text. */
std::string evalAppUsage(const std::string& programName);
}  // namespace immslam::evalapp
