/* imm-monoslam — the imm-render program as a library function (so tests can run it). */
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::sim
{
/** `imm-render SCENARIO.ini OUT_FOLDER [--frames N] [--seed S] [--set SECTION.KEY=VALUE]... [--help]`:
 * renders a scenario to a dataset folder (CSimulator::writeDataset) and prints the frames written
 * and the frame rate.
 * \param args the arguments after the program name.
 * \return 0 on success, 1 on bad input or failure (the message names the file/key), 2 on bad usage. */
int runRenderApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/** The usage text. */
std::string renderAppUsage();
}  // namespace immslam::sim
