/* imm-monoslam — static/dynamic decisions (classifications.csv) scored against ground truth:
 * the renderer's object masks or the projected ground-truth points of a simulated data set. */
#pragma once

#include <immslam/eval/alignment.h>
#include <immslam/core/point_tracks.h>
#include <immslam/eval/classification.h>
#include <immslam/math/types.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <iosfwd>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace immslam::eval
{
/** One shadow-filter decision (a row of classifications.csv). */
struct TClassificationDecision
{
  double timestamp = 0;                         ///< frame time (s)
  std::int64_t featureId = 0;                   ///< the feature's id
  EMotionClass decided = EMotionClass::Static;  ///< the filter's class
  Vec2 uv = Vec2::Zero();                       ///< measured pixel (u, v) in that frame
};

/** Reads classifications.csv: header `timestamp,feature_id,class,u,v` (extra columns at the end
 * are ignored), class `static` or `dynamic`.
 * \throws std::runtime_error naming `file:line` for a bad header, a missing field, a value that is
 *         not a number or an unknown class, and naming the file when it cannot be opened. */
std::vector<TClassificationDecision> readClassificationsCsv(const std::string& path);

/** Decisions scored against ground truth. */
struct TClassificationResult
{
  TConfusionMatrix confusion;  ///< decisions that have a ground truth
  std::size_t unmatched = 0;   ///< decisions without one (no truth at that time or place)

  /** confusion.summary() plus the unmatched count. */
  std::string summary() const;
};

/** Prints TClassificationResult::summary(). */
std::ostream& operator<<(std::ostream& os, const TClassificationResult& r);

/** The truth of one decision, or std::nullopt when there is none (counted as unmatched). */
using TClassificationTruth = std::function<std::optional<EMotionClass>(const TClassificationDecision&)>;

/** Scores every decision against truth(decision). */
TClassificationResult evaluateClassifications(const std::vector<TClassificationDecision>& decisions,
                                              const TClassificationTruth& truth);

/** An object mask: 0 = static world, > 0 = a moving object (the renderer writes the object id). */
struct TMaskImage
{
  int width = 0;                     ///< columns
  int height = 0;                    ///< rows
  std::vector<std::uint8_t> pixels;  ///< row-major, width * height values

  /** Copies a single-channel 8-bit buffer with rows strideBytes apart (e.g. a CV_8UC1 cv::Mat:
   * fromBuffer(m.data, m.cols, m.rows, m.step)). */
  static TMaskImage fromBuffer(const std::uint8_t* data, int width, int height, std::size_t strideBytes);

  /** Value at pixel (u, v) (integers, 0-based; no bounds check beyond the vector's). */
  std::uint8_t at(int u, int v) const { return pixels[static_cast<std::size_t>(v) * static_cast<std::size_t>(width) + static_cast<std::size_t>(u)]; }

  /** True if any pixel of the (2 radius + 1)^2 neighbourhood of the pixel nearest (u, v)
   * (lround, doc/conventions.md: (0, 0) is the centre of the top-left pixel) is non-zero;
   * neighbours outside the image are ignored (a point off the image is static). */
  bool movingNear(const Vec2& uv, int radius = 1) const;
};

/** Reads a mask image (PNG or any format OpenCV reads; any depth; with colour channels a pixel is
 * non-zero if any colour channel is, an alpha channel being ignored).
 * \throws std::runtime_error naming the file when it cannot be read. */
TMaskImage readMaskImage(const std::string& path);

/** A mask per timestamp, or std::nullopt when there is none for that time. */
using TMaskProvider = std::function<std::optional<TMaskImage>(double timestamp)>;

/** Scores decisions against object masks: a decision is truly dynamic if maskAt(timestamp)
 * movingNear(uv, radius), static otherwise; unmatched if maskAt returns nullopt. maskAt is called
 * once per run of consecutive decisions with the same timestamp.
 * \throws std::invalid_argument if radius < 0. */
TClassificationResult classificationAgainstMasks(const std::vector<TClassificationDecision>& decisions,
                                                 const TMaskProvider& maskAt, int radius = 1);

/** The masks of a rendered dataset folder (imm-render, imm-composite): rgb.txt gives the image file
 * of each timestamp (`timestamp rgb/NAME`), its mask is masks/NAME; a timestamp not within maxDt of
 * an rgb.txt entry has no mask (std::nullopt). rgb.txt is read here, each mask when asked for.
 * \throws std::runtime_error naming the file for a missing rgb.txt or masks/ folder or a malformed
 *         rgb.txt line (file:line); the provider throws naming the file for an unreadable mask. */
TMaskProvider maskFolderProvider(const std::string& datasetFolder, double maxDt = 1e-4);

/** classificationAgainstMasks() with the masks of a rendered dataset folder: rgb.txt gives the
 * image file of each timestamp (`timestamp rgb/NAME`), its mask is masks/NAME. Decisions whose
 * timestamp is not within maxDt of an rgb.txt entry are unmatched.
 * \throws std::runtime_error naming the file for a missing rgb.txt or masks/ folder, a malformed
 *         rgb.txt line (file:line) or an unreadable mask. */
TClassificationResult classificationAgainstMaskFolder(const std::vector<TClassificationDecision>& decisions,
                                                      const std::string& datasetFolder, int radius = 1,
                                                      double maxDt = 1e-4);

/** Reads points_groundtruth.txt (../shared/data/monoslammot_synth19): lines
 * `timestamp point_id kind x y z u v`, kind `static` or `moving`, '#' comments.
 * \throws std::runtime_error naming `file:line` for a malformed line or unknown kind. */
std::vector<core::TGroundTruthPoint> readPointsGroundTruth(const std::string& path);

/** Scores decisions against projected ground-truth points: the truth of a decision is the kind of
 * the point nearest to its pixel among the points of the frame within maxDt of its timestamp,
 * if that point is at most radiusPx away; otherwise (another corner, or no points at that time)
 * the decision is unmatched.
 * \throws std::invalid_argument if radiusPx is negative or NaN. */
TClassificationResult classificationAgainstPoints(const std::vector<TClassificationDecision>& decisions,
                                                  const std::vector<core::TGroundTruthPoint>& points,
                                                  double radiusPx = 3.0, double maxDt = 1e-4);

/** Reads tracks.csv: header starting `timestamp,feature_id,x,y,z,u,v`, optional columns `range`
 * and `range_rel_sigma` anywhere after them (other columns ignored).
 * \throws std::runtime_error naming `file:line` for a bad header, a missing field or a value that
 *         is not a number, and naming the file when it cannot be opened. */
std::vector<core::TTrackSample> readTracksCsv(const std::string& path);

/** Tracked positions of dynamic features against the moving ground-truth points. */
struct TTrackErrorResult
{
  std::size_t samples = 0;        ///< rows read
  std::size_t tracks = 0;         ///< distinct feature ids
  std::size_t matched = 0;        ///< rows whose nearest ground-truth point is a moving one
  std::size_t matchedTracks = 0;  ///< distinct feature ids among them
  std::size_t onStatic = 0;       ///< rows whose nearest ground-truth point is static
  std::size_t unmatched = 0;      ///< rows with no ground-truth point within the radius
  std::size_t uncertain = 0;      ///< moving-point rows left out: relative sigma above the limit (or unknown)
  double maxRelativeSigma = std::numeric_limits<double>::infinity();  ///< the limit used
  double rmse = 0;                ///< RMS of |S(p_est) - p_gt| over the matched rows kept (gt units)
  double median = 0;              ///< median of the same
  double max = 0;                 ///< largest
  double medianRange = std::numeric_limits<double>::quiet_NaN();  ///< median distance from the camera of those rows (gt units; NaN without the column)
  /** Multi-line report. */
  std::string summary() const;
};

/** Position error of tracked dynamic features: each row is associated, like a decision in
 * classificationAgainstPoints(), with the ground-truth point nearest to its pixel in its frame
 * (within radiusPx, frames within maxDt); for a moving point the error is |S(p_W) - p_gt| where S
 * maps the estimate's world frame onto the ground truth's (the Sim(3) of the camera trajectory's
 * alignment, computeAte().sim3()). With a finite maxRelativeSigma, rows on a moving point whose
 * core::TTrackSample::rangeRelSigma exceeds it (or is unknown) are counted as uncertain and left out:
 * a bearing-only track locates its point only once the motion has given it parallax.
 * \throws std::invalid_argument if radiusPx is negative or NaN, or maxRelativeSigma is NaN or <= 0. */
TTrackErrorResult trackErrorAgainstPoints(const std::vector<core::TTrackSample>& samples,
                                          const std::vector<core::TGroundTruthPoint>& points, const TSim3& alignment,
                                          double radiusPx = 3.0, double maxDt = 1e-4,
                                          double maxRelativeSigma = std::numeric_limits<double>::infinity());
}  // namespace immslam::eval
