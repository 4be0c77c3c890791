/* imm-monoslam — the slam-eval program as a library function (apps/slam-eval's main is a thin wrapper). */
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::eval
{
/** Runs `slam-eval`, the evaluation of imm-monoslam's outputs against ground truth:
 * - `slam-eval ate EST.txt GT.txt [--sim3|--se3|--no-align] [--max-dt S] [--rpe DELTA] [--json]`:
 *   ATE after alignment (and RPE) of TUM trajectories (runEvalApp(); `slam-eval EST.txt GT.txt ...`
 *   is the same, the old imm-eval form);
 * - `slam-eval segmentation model_probabilities.csv motion_labels.txt [--exclude S] [--max-dt S]`:
 *   segmentationAccuracy();
 * - `slam-eval classification classifications.csv (--masks DATASET_FOLDER | --points
 *   points_groundtruth.txt) [--radius PX] [--max-dt S]`: classificationAgainstMaskFolder() or
 *   classificationAgainstPoints();
 * - `slam-eval nis searches.csv [--confidence C]`: computeSearchNis();
 * - `slam-eval --help`, `slam-eval COMMAND --help`.
 * \param args the command line, args[0] being the program name.
 * \param out  reports and help texts.
 * \param err  error messages.
 * \return exit status: 0 success, 1 bad input (the message names the file, and the line for a
 *         malformed one), 2 bad usage. Never exits the process. */
int runSlamEvalApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/** The `slam-eval --help` text. */
std::string slamEvalAppUsage(const std::string& programName);
}  // namespace immslam::eval
