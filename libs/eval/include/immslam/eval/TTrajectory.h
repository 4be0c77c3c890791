/* imm-monoslam — timestamped poses (TUM format) shared by outputs, ground truth and evaluation. */
#pragma once

#include <immslam/math/types.h>

#include <string>
#include <vector>

namespace immslam::eval
{
/** One pose T_W_C: camera position p_W_C and orientation q_W_C = [qw qx qy qz] (math/quaternion.h). */
struct TStampedPose
{
  double timestamp = 0;
  Vec3 p_W_C = Vec3::Zero();
  Vec4 q_W_C = Vec4(1, 0, 0, 0);
};

using TTrajectory = std::vector<TStampedPose>;

/** Reads a TUM file `timestamp tx ty tz qx qy qz qw` ('#' comments, blank lines skipped).
 * \throws std::runtime_error naming the file and line of a malformed entry. */
TTrajectory readTumTrajectory(const std::string& path);

/** Writes a TUM file (timestamps with 6 decimals, positions/quaternions with 9 significant digits). */
void writeTumTrajectory(const TTrajectory& traj, const std::string& path);

/** One TUM line for a pose (no newline). */
std::string formatTumLine(const TStampedPose& p);
}  // namespace immslam::eval
