/* imm-monoslam — normalized innovation squared (NIS) of the matches used by the SLAM update, from
 * the app's searches.csv (real data: no ground truth needed). */
#pragma once

#include <immslam/math/types.h>

#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace immslam::eval
{
/** Outcome of one active search (searches.csv `status`). */
enum class ESearchStatus
{
  NotFound,  ///< no match inside the search region
  Inlier,    ///< low-innovation inlier of the 1-point RANSAC: used in the update
  Rescued,   ///< high-innovation match rescued after the first update: used in the update
  Rejected   ///< matched but rejected as an outlier (not used)
};

/** Name as written in searches.csv: not_found, inlier, rescued, rejected. */
const char* searchStatusName(ESearchStatus s);

/** One row of searches.csv: the prediction h and innovation covariance S of a feature, and the
 * match z if one was found. */
struct TSearchRow
{
  double timestamp = 0;       ///< frame time (s)
  std::int64_t featureId = 0;  ///< the feature's id
  Vec2 h = Vec2::Zero();      ///< predicted pixel (h_u, h_v)
  Mat2 S = Mat2::Zero();      ///< innovation covariance (px^2) used for the search and the update
  bool found = false;         ///< a match was found
  Vec2 z = Vec2::Zero();      ///< matched pixel (meaningful when found)
  double score = 0;           ///< match score
  ESearchStatus status = ESearchStatus::NotFound;  ///< what the update did with it

  /** True for the matches used in the update (Inlier or Rescued). */
  bool usedInUpdate() const { return status == ESearchStatus::Inlier || status == ESearchStatus::Rescued; }
};

/** Reads searches.csv (written with `[output] search_log = true`): header
 * `timestamp,feature_id,h_u,h_v,s_uu,s_uv,s_vv,found,z_u,z_v,score,status` (extra columns at the
 * end are ignored). Numbers may be nan/inf (e.g. z of a failed search).
 * \throws std::runtime_error naming `file:line` for a bad header, field count, number or status,
 *         and naming the file when it cannot be opened. */
std::vector<TSearchRow> readSearchesCsv(const std::string& path);

/** NIS of one measurement: \f$ (z-h)^\top S^{-1} (z-h) \f$ (Bar-Shalom et al., sec. 5.4.2);
 * +infinity if S is not positive definite or a value is not finite. */
double innovationNis(const Vec2& z, const Vec2& h, const Mat2& S);

/** NIS statistics of the matches used in the updates. For a consistent filter each NIS is
 * chi-square with 2 degrees of freedom: mean 2 (1 per dof), and a fraction `confidence` of the
 * values lies below \f$ \chi^2_2(\mathrm{confidence}) = -2 \ln(1 - \mathrm{confidence}) \f$
 * (5.991 for 95 %). */
struct TNisResult
{
  std::size_t nSearches = 0;  ///< rows read
  std::size_t nUsed = 0;      ///< matches used in the update (status inlier or rescued)
  std::size_t nInvalid = 0;   ///< used matches whose S is not positive definite (infinite NIS)
  std::size_t nInside = 0;    ///< used matches with NIS <= bound (invalid ones are outside)
  double confidence = 0.95;   ///< probability of the bound
  double bound = 0;           ///< chi-square(2) quantile of confidence
  double meanNis = 0;         ///< mean over the valid used matches (NaN if none)
  double meanNisPerDof = 0;   ///< meanNis / 2 (ideally 1)
  double medianNis = 0;       ///< median over the valid used matches (ideally 2 ln 2 = 1.386)
  double fractionInside = 0;  ///< nInside / nUsed (ideally confidence; NaN if nUsed = 0)
  std::vector<double> values;  ///< NIS of every used match, in row order (invalid ones +inf)

  /** Multi-line human-readable report. */
  std::string summary() const;
};

/** Computes the NIS of every row used in the update (TSearchRow::usedInUpdate()).
 * \throws std::invalid_argument unless 0 < confidence < 1. */
TNisResult computeSearchNis(const std::vector<TSearchRow>& rows, double confidence = 0.95);

/** Prints TNisResult::summary(). */
std::ostream& operator<<(std::ostream& os, const TNisResult& r);
}  // namespace immslam::eval
