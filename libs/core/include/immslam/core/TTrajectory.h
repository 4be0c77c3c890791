/* imm-monoslam — timestamped poses (TUM format) shared by outputs, ground truth and evaluation. */
#pragma once

#include <immslam/math/types.h>

#include <string>
#include <vector>

namespace immslam::core
{
/** One pose T_W_C: camera position p_W_C and orientation q_W_C = [qw qx qy qz] (math/quaternion.h). */
struct TStampedPose
{
  double timestamp = 0;           ///< seconds (the input frame's own time)
  Vec3 p_W_C = Vec3::Zero();      ///< camera centre in W
  Vec4 q_W_C = Vec4(1, 0, 0, 0);  ///< orientation, scalar first, unit norm
};

/** A trajectory: poses in file (usually time) order. */
using TTrajectory = std::vector<TStampedPose>;

/** Reads a TUM file `timestamp tx ty tz qx qy qz qw` (one pose a line; fields separated by spaces,
 * tabs or commas; lines whose first non-blank character is '#' and blank lines are skipped).
 * The file's quaternion order qx qy qz qw is converted to our [qw qx qy qz] and normalized.
 * Poses are returned in file order (not sorted).
 * \throws std::runtime_error naming `file:line` for a line without exactly 8 finite numbers or
 *         with a zero quaternion, and naming the file when it cannot be opened. */
TTrajectory readTumTrajectory(const std::string& path);

/** Writes a TUM file, one formatTumLine() per pose, no header.
 * \throws std::runtime_error naming the file when it cannot be written. */
void writeTumTrajectory(const TTrajectory& traj, const std::string& path);

/** One TUM line `timestamp tx ty tz qx qy qz qw` for a pose (no newline). The timestamp is printed
 * with 6 decimals (like "%.6f"); positions and quaternion components with the shortest decimal
 * form that reads back to the identical double (std::to_chars), so a write/read round trip is
 * exact. Locale independent. */
std::string formatTumLine(const TStampedPose& p);

/** The pose at time t on the constant-velocity path from a to b: the position linear in time, the
 * orientation on the shorter great circle (slerp); a's pose before a's time, b's after b's (with
 * timestamp t in every case). */
TStampedPose interpolatePose(const TStampedPose& a, const TStampedPose& b, double t);

/** p moved rigidly as `from` is moved onto `to` (to from^-1 p): p's pose relative to `from`, kept
 * relative to `to`; p's timestamp. */
TStampedPose carryPose(const TStampedPose& to, const TStampedPose& from, const TStampedPose& p);

/** A pose for every timestamp of `all` (time order) from the poses of `placed` (a subset of its
 * timestamps, to 1 microsecond, in time order): a placed pose as it is; between two placed poses the
 * pose interpolated in time (interpolatePose); before the first or after the last placed pose, the
 * nearest one carried by `all`'s motion from it (carryPose). `all` itself when `placed` is empty. */
TTrajectory completeTrajectory(const TTrajectory& placed, const TTrajectory& all);

/** The positions p_W_C of a trajectory, in order. */
std::vector<Vec3> trajectoryPositions(const TTrajectory& traj);
}  // namespace immslam::core
