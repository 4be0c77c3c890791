/* imm-monoslam — the imm-eval program as a library function (the app's main is a thin wrapper). */
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::eval
{
/** Runs `imm-eval EST.txt GT.txt [--sim3|--se3|--no-align] [--max-dt S] [--rpe DELTA] [--json]`:
 * reads two TUM trajectories, computes the ATE (computeAte) and prints it as text or JSON to out.
 * \param args the command line, args[0] being the program name.
 * \param out  report (and --help text).
 * \param err  error messages.
 * \return exit status: 0 success, 1 bad input (unreadable/malformed file, named in the message,
 *         or no associated poses), 2 bad usage. Never exits the process. */
int runEvalApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/** The --help text. */
std::string evalAppUsage(const std::string& programName);
}  // namespace immslam::eval
