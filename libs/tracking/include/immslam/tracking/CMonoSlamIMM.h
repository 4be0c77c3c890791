/* imm-monoslam — IMM monocular EKF SLAM (Civera, Davison & Montiel, "Interacting Multiple Model
 * Monocular SLAM", ../shared/papers/imm-monocular-slam.md): the image-free filter (CImmSlamFilter)
 * driven by its tracker (CSlamTracker). CMonoSlamIMM is the name the system and the applications use
 * for the pair: the tracker, which owns the filter (CSlamTracker::filter()). */
#pragma once

#include <immslam/slam/CImmSlamFilter.h>
#include <immslam/tracking/CSlamTracker.h>
#include <immslam/slam/TFeatureWorldEstimate.h>
#include <immslam/slam/TFrameReport.h>
#include <immslam/slam/TIMMBankOptions.h>

namespace immslam::slam
{
/** The IMM monocular SLAM: the tracker with its filter. */
using CMonoSlamIMM = CSlamTracker;
}  // namespace immslam::slam
