/* imm-monoslam — consistency of the SLAM filter's relative poses (relative_poses.csv, written with
 * [output] relative_pose_lag) against ground truth: the NEES of each reported motion T_{C_j C_k}
 * with the filter's own covariance (Bar-Shalom et al., sec. 5.4.2). */
#pragma once

#include <immslam/core/TTrajectory.h>
#include <immslam/math/types.h>

#include <string>
#include <vector>

namespace immslam::eval
{
/** One row of relative_poses.csv: the camera's motion from the frame at fromTimestamp to the frame at
 * timestamp, T_{C_j C_k} (p_Cj = R(q) p_Ck + t, the map's units), and the covariance of
 * [dt; dtheta] (t = t_hat + dt, R = R_hat Exp(dtheta)). */
struct TRelativePoseRow
{
  double timestamp = 0, fromTimestamp = 0;
  Vec3 t = Vec3::Zero();
  Vec4 q = Vec4(1, 0, 0, 0);  ///< [qw qx qy qz]
  Mat6 cov = Mat6::Zero();
};

/** Reads relative_poses.csv: header `timestamp,from_timestamp,tx,ty,tz,qx,qy,qz,qw,c00,c01,...,c55`
 * (the upper triangle of the covariance, row by row).
 * \throws std::runtime_error naming `file:line` for a bad header, field count or number, and the file
 *         when it cannot be opened. */
std::vector<TRelativePoseRow> readRelativePosesCsv(const std::string& path);

/** NEES statistics of the relative poses. For a consistent filter the rotation NEES is chi-square
 * with 3 degrees of freedom and the full one with 6. The translation is in the map's units: the full
 * NEES needs the scale of the map (ground-truth units per map unit, from a Sim(3) alignment of the
 * run's trajectory); without it only the rotation's is computed. */
struct TRelativeNeesResult
{
  std::size_t nRows = 0;     ///< rows read
  std::size_t nUsed = 0;     ///< rows whose two timestamps have a ground-truth pose
  double confidence = 0.95;  ///< probability of the chi-square bounds
  double scale = 0;          ///< ground-truth units per map unit (0: not known, rotation only)
  std::vector<double> rotation;  ///< rotation NEES (3 dof) of every used row
  std::vector<double> full;      ///< full NEES (6 dof) of every used row (empty without scale)
  /** Multi-line human-readable report: mean, median, fraction inside the bound, each against its
   * chi-square value. */
  std::string summary() const;
};

/** The NEES of every row against gt (T_W_C poses, associated within maxDt).
 * \param scale ground-truth units per map unit (<= 0: rotation only).
 * \throws std::invalid_argument unless 0 < confidence < 1 and maxDt >= 0. */
TRelativeNeesResult computeRelativeNees(const std::vector<TRelativePoseRow>& rows, const core::TTrajectory& gt,
                                        double scale, double maxDt = 1e-4, double confidence = 0.95);
}  // namespace immslam::eval
