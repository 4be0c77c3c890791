/* imm-monoslam — the slam-eval program as a library function (apps/slam-eval's main is a thin wrapper). */
#pragma once

#include <immslam/eval/classification_truth.h>

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::evalapp
{
/** Ground truth that this library cannot compute itself: the renderer (libs/sim) depends on eval,
 * so apps/slam-eval hands its functions in. Empty members make the features that need them a
 * usage error. */
struct TSlamEvalTruthSources
{
  /** The true points at the pixels of tracked samples of a dataset folder written by imm-render
   * (sim::truthAtPixelsOfRenderedFolder): (folder, samples, maxDt, report) -> points at the
   * samples' own pixels; `report` receives one line on the samples left out. */
  std::function<std::vector<core::TGroundTruthPoint>(const std::string&, const std::vector<core::TTrackSample>&, double,
                                               std::string&)>
      renderedTrackTruth;
};

/** Runs `slam-eval`, the evaluation of imm-monoslam's outputs against ground truth:
 * - `slam-eval ate EST.txt GT.txt [--sim3|--se3|--no-align] [--max-dt S] [--rpe DELTA [--rpe-csv F]] [--json]`:
 *   ATE after alignment (and RPE) of TUM trajectories (runEvalApp(); `slam-eval EST.txt GT.txt ...`
 *   is the same, the old imm-eval form);
 * - `slam-eval segmentation model_probabilities.csv motion_labels.txt [--exclude S] [--max-dt S]`:
 *   segmentationAccuracy();
 * - `slam-eval classification classifications.csv (--masks DATASET_FOLDER | --points
 *   points_groundtruth.txt) [--radius PX] [--max-dt S]`: classificationAgainstMaskFolder() or
 *   classificationAgainstPoints();
 * - `slam-eval tracks tracks.csv (points_groundtruth.txt | RENDERED_FOLDER) --est EST.txt [--gt GT.txt]`:
 *   trackErrorAgainstPoints(), the truth of a rendered folder from truth.renderedTrackTruth;
 * - `slam-eval nis searches.csv [--confidence C]`: computeSearchNis();
 * - `slam-eval --help`, `slam-eval COMMAND --help`.
 * \param args the command line, args[0] being the program name.
 * \param out  reports and help texts.
 * \param err  error messages.
 * \param truth ground truth from outside this library (see TSlamEvalTruthSources).
 * \return exit status: 0 success, 1 bad input (the message names the file, and the line for a
 *         malformed one), 2 bad usage. Never exits the process. */
int runSlamEvalApp(const std::vector<std::string>& args, std::ostream& out, std::ostream& err,
                   const TSlamEvalTruthSources& truth = {});

/** The `slam-eval --help` text. */
std::string slamEvalAppUsage(const std::string& programName);
}  // namespace immslam::evalapp
