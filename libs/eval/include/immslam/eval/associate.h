/* imm-monoslam — timestamp association of two trajectories (estimate vs ground truth). */
#pragma once

#include <immslam/core/TTrajectory.h>

#include <cstddef>
#include <utility>
#include <vector>

namespace immslam::eval
{
/** Pairs poses of a and b whose timestamps differ by at most maxDt seconds, one-to-one.
 *
 * Candidates are each pose and its immediate predecessor and successor in time in the other
 * trajectory; they are accepted greedily in order of increasing |t_a - t_b| (ties by index), each
 * pose being used at most once. Whenever either trajectory's poses are more than 2 maxDt apart
 * (the usual case: maxDt below half a frame period) this equals the exhaustive greedy matching of
 * TUM's associate.py. Cost O(n log n). Poses with non-finite timestamps are never paired;
 * neither input needs to be sorted.
 * \param maxDt largest accepted |t_a - t_b| in seconds (>= 0).
 * \return pairs (index into a, index into b), sorted by a's timestamp.
 * \throws std::invalid_argument if maxDt is negative or NaN. */
std::vector<std::pair<size_t, size_t>> associateByTimestamp(
    const core::TTrajectory& a, const core::TTrajectory& b, double maxDt = 0.01);
}  // namespace immslam::eval
