/* imm-monoslam — motion segmentation accuracy of the IMM bank (model probabilities vs true labels). */
#pragma once

#include <immslam/math/types.h>

#include <cstddef>
#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::eval
{
/** The family of a motion model: its name up to the first '_' ("rotation_0.5px" -> "rotation",
 * "stationary" -> "stationary"). The shipped families are stationary, rotation and general
 * (CONTRACT.md: model names begin with their family). */
std::string modelFamily(const std::string& modelName);

/** The content of model_probabilities.csv: the posterior model probabilities mu_k per frame. */
struct TModelProbabilities
{
  std::vector<std::string> modelNames;  ///< the columns after `timestamp`, in file order
  std::vector<double> times;            ///< one timestamp (s) per row, in file order
  MatX probs;                           ///< T x r: probs(k, j) = mu_j at times[k]
};

/** Reads model_probabilities.csv: a header `timestamp,<model name>...` (at least one model), then
 * one row per frame with as many finite numbers. Blank lines and '#' lines are skipped.
 * \throws std::runtime_error naming `file:line` for a bad header, a wrong field count or a
 *         value that is not a finite number, and naming the file when it cannot be opened. */
TModelProbabilities readModelProbabilitiesCsv(const std::string& path);

/** Summed probability of each family (paper: the IMM's fused belief in a kind of motion). */
struct TFamilyProbabilities
{
  std::vector<std::string> families;  ///< distinct families in order of first column
  MatX probs;                         ///< T x F: sum of the probabilities of the family's models
};

/** Sums the columns of probs (T x r) per modelFamily() of modelNames (in column order).
 * \throws std::invalid_argument if probs does not have modelNames.size() columns. */
TFamilyProbabilities familyProbabilities(const std::vector<std::string>& modelNames, const MatX& probs);

/** True camera motion labels per timestamp (the renderer's motion_labels.txt). */
struct TMotionLabels
{
  std::vector<double> times;        ///< seconds, in file order
  std::vector<std::string> labels;  ///< stationary, rotation or general
};

/** Reads motion_labels.txt: lines `timestamp label` with label stationary, rotation or general;
 * '#' comment lines and blank lines are skipped.
 * \throws std::runtime_error naming `file:line` for a malformed line or an unknown label, and
 *         naming the file when it cannot be opened. */
TMotionLabels readMotionLabels(const std::string& path);

/** The label of each time: that of the labels' timestamp nearest to it if within maxDt seconds,
 * else the empty string (no label). */
std::vector<std::string> labelsAtTimes(const TMotionLabels& labels, const std::vector<double>& times,
                                       double maxDt = 1e-4);

/** Result of segmentationAccuracy(). */
struct TSegmentationResult
{
  double accuracy = 0;        ///< nCorrect / nCounted (NaN if nothing was counted)
  std::size_t nFrames = 0;    ///< frames given
  std::size_t nCounted = 0;   ///< labelled frames outside every exclusion window
  std::size_t nCorrect = 0;   ///< counted frames whose most probable family equals the label
  std::size_t nExcluded = 0;  ///< labelled frames inside an exclusion window
  std::size_t nUnlabelled = 0;   ///< frames without a label (never counted)
  double excludeAroundTransitionsS = 0.5;  ///< exclusion half-width used (s)
  std::vector<double> transitions;  ///< times of the label changes (the first frame of each new label)
  /** Classes of the confusion matrix: the model families in column order, then any label that is
   * no family (always wrong). */
  std::vector<std::string> classes;
  /** confusion[i][j]: counted frames labelled classes[i] whose most probable family is classes[j]. */
  std::vector<std::vector<std::size_t>> confusion;

  /** confusion entry by names (0 if either is not a class). */
  std::size_t count(const std::string& truth, const std::string& decided) const;
  /** Counted frames labelled `truth`. */
  std::size_t labelled(const std::string& truth) const;
  /** Per-label accuracy: frames of that label decided correctly / frames of that label (NaN if none). */
  double recall(const std::string& truth) const;
  /** Multi-line human-readable report: accuracy, counts and the confusion table. */
  std::string summary() const;
};

/** Motion segmentation accuracy of an IMM bank (IMM paper, Sec. VI: the model probabilities
 * follow the true kind of motion). For each frame k the decided family is the one with the
 * highest summed probability (familyProbabilities(); ties go to the earlier family) and is
 * compared with labels[k]. Frames closer than excludeAroundTransitionsS (strictly) to a label
 * change are not counted: the filter needs a few frames to notice a change of motion, and
 * near-still motion at the boundary of a segment is ambiguous. A label change happens at
 * times[k] when labels[k] differs from the label of the previous labelled frame (in the given
 * order, normally increasing time).
 * \param times        frame timestamps (s), one per row of probs.
 * \param modelNames   model names (columns of probs); families by modelFamily().
 * \param probs        T x r model probabilities.
 * \param labels       true label per frame (stationary|rotation|general); "" = no label.
 * \param excludeAroundTransitionsS half-width of the exclusion window (s, >= 0; 0 excludes nothing).
 * \throws std::invalid_argument if the sizes do not match or the window is negative or NaN. */
TSegmentationResult segmentationAccuracy(const std::vector<double>& times, const std::vector<std::string>& modelNames,
                                         const MatX& probs, const std::vector<std::string>& labels,
                                         double excludeAroundTransitionsS = 0.5);

/** segmentationAccuracy() of read files: each row of p gets the label of the nearest labelled
 * timestamp within maxDt (labelsAtTimes()). Rows without a label are reported as unlabelled.
 * \throws std::invalid_argument as above; std::runtime_error if no row has a label. */
TSegmentationResult segmentationAccuracy(const TModelProbabilities& p, const TMotionLabels& labels,
                                         double excludeAroundTransitionsS = 0.5, double maxDt = 1e-4);

/** Prints TSegmentationResult::summary(). */
std::ostream& operator<<(std::ostream& os, const TSegmentationResult& r);
}  // namespace immslam::eval
