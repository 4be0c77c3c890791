/* imm-monoslam — an online keyframe smoother behind the filter: a sliding window of keyframes, each
 * with the filter's pose and the matches the filter used in its update at that frame, refined by
 * bundleAdjust() in a background thread; every frame's smoothed pose is its keyframe's smoothed
 * pose composed with the filter's motion since that keyframe. The filter never waits for it. */
#pragma once

#include <immslam/core/TTrajectory.h>
#include <immslam/math/types.h>
#include <immslam/refine/bundle_adjust.h>

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

namespace immslam::refine
{
/** One match the filter used in its update: the feature and its measured pixel, undistorted and
 * normalised (x/z, y/z of the camera frame). */
struct TSmootherMatch
{
  std::int64_t featureId = 0;
  Vec2 xn = Vec2::Zero();
};

/** What the smoother receives per frame: the filter's pose T_W_C and the matches of its update. */
struct TSmootherFrame
{
  core::TStampedPose pose;
  std::vector<TSmootherMatch> matches;
};

/** A keyframe as published: its frame, the filter's pose and the smoothed one. */
struct TSmoothedKeyframe
{
  std::size_t frame = 0;            ///< index of the frame (0 = first frame given)
  core::TStampedPose filterPose;    ///< T_W_C of the filter at that frame
  core::TStampedPose smoothedPose;  ///< T_W_C after the latest window optimisation
  bool optimised = false;           ///< smoothedPose came out of at least one window optimisation
};

/** The smoother's cost: lag of its publications and the CPU time of its optimisations. */
struct TSmootherStats
{
  std::size_t frames = 0, keyframes = 0, optimisations = 0;
  std::vector<double> lagFrames;  ///< per optimised keyframe: frames given between its arrival and
                                  ///< its first optimised publication
  double cpuSeconds = 0;          ///< CPU time of the smoother's thread (or of its calls when synchronous)
};

/** Sliding-window keyframe smoother (a fixed-lag bundle adjustment, Triggs et al. 2000, over the
 * filter's own matches).
 *
 * Keyframes: the first frame with at least TOptions::minMatches matches, then a frame when fewer
 * than TOptions::minOverlap of its matches were measured at the last keyframe (the view has
 * changed), or TOptions::maxFrameGap frames after it, provided the features it shares with the last
 * keyframe moved by TOptions::minParallaxPx once the filter's rotation is taken out (or it shares
 * fewer than minMatches: the view is new). A new keyframe starts at the last keyframe's smoothed pose
 * composed with the filter's relative motion between the two.
 *
 * Window: the last TOptions::windowKeyframes keyframes; every feature measured by at least
 * TOptions::minViews of them is triangulated from the current poses (triangulateAll()), then poses
 * and points are bundle-adjusted (bundleAdjust(), Huber cost); the TOptions::heldKeyframes oldest
 * keyframes of the window hold the gauge, their scale included, so the window continues the frame
 * and scale of the keyframes before it (over the span of many keyframes: a pair of close ones would
 * relay the scale poorly). Until the window has slid past them, the held ones are the filter's first
 * keyframes as they came. A keyframe leaving the window keeps its last smoothed pose.
 *
 * Threads: addFrame() only moves the frame into a queue under a mutex; a worker thread takes the
 * queued frames one by one, picks keyframes and optimises the window at every keyframe (skipped
 * while it is behind by more than TOptions::maxBacklogFrames). With TOptions::synchronous,
 * addFrame() does that work itself. Both give the same result while the worker keeps up. */
class CKeyframeSmoother
{
 public:
  struct TOptions
  {
    std::size_t windowKeyframes = 20;  ///< keyframes optimised together
    std::size_t heldKeyframes = 5;     ///< oldest keyframes of the window held fixed (gauge and scale)
    double minOverlap = 0.7;           ///< a new keyframe when less of a frame's matches were at the last one
    std::size_t maxFrameGap = 3;       ///< a new keyframe at most this many frames after the last one
    std::size_t minMatches = 8;        ///< a frame with fewer matches is never a keyframe
    /** A frame sharing features with the last keyframe becomes one only if their median parallax
     * (bearing change once the filter's rotation is taken out, pixels) reaches this: a camera at rest
     * or panning adds no keyframe whose position the images could not fix. */
    double minParallaxPx = 1;
    int minViews = 3;                  ///< keyframes that must measure a feature for it to enter the window
    double huberPx = 2;                ///< Huber threshold of the cost (pixels)
    int maxIterations = 15;            ///< Levenberg-Marquardt iterations per window optimisation
    /** The worker skips the optimisation of a keyframe while more frames than this wait in its
     * queue (a later keyframe's optimisation covers it): the lag stays bounded on a slow machine.
     * While it keeps up, the result is that of a synchronous run. */
    std::size_t maxBacklogFrames = 30;
    int workerNice = 10;               ///< nice value of the worker thread (0: the caller's priority)
    bool synchronous = false;          ///< no thread: addFrame() optimises before it returns
  };

  /** \param fx, fy the camera's focal lengths (pixels): the residual scale of the Huber threshold. */
  CKeyframeSmoother(const TOptions& opts, double fx, double fy);
  /** Stops the worker (as finish(), the queued frames are still processed). */
  ~CKeyframeSmoother();
  CKeyframeSmoother(const CKeyframeSmoother&) = delete;
  CKeyframeSmoother& operator=(const CKeyframeSmoother&) = delete;

  /** Hands a frame over (never waits for an optimisation). Frames must come in time order.
   * \throws std::logic_error after finish(). */
  void addFrame(TSmootherFrame frame);

  /** The keyframes as published so far (a copy, safe while the worker runs: for a live scene). */
  std::vector<TSmoothedKeyframe> keyframes() const;

  /** Processes every queued frame, runs the last window optimisation, stops the worker. */
  void finish();

  /** Every frame given, smoothed: its keyframe's (the last one at or before it, or the first
   * keyframe) smoothed pose composed with the filter's motion from that keyframe. The filter's
   * poses when there is no keyframe. Call after finish(). */
  core::TTrajectory trajectory() const;

  /** Lag and CPU time so far. */
  TSmootherStats stats() const;

 private:
  struct TKeyframe
  {
    TSmoothedKeyframe pub;
    std::vector<TSmootherMatch> matches;
  };

  void run();
  /** Picks keyframes among `frame`; \return true if it became one. Worker or synchronous caller. */
  bool ingest(TSmootherFrame&& frame);
  /** Per feature `frame` shares with `kf`: its bearing change once the filter's rotation between
   * the two is taken out (pixels). */
  std::vector<double> parallaxPx(const TKeyframe& kf, const TSmootherFrame& frame) const;
  /** Bundle-adjusts the window and publishes its poses. */
  void optimiseWindow();

  TOptions m_opts;
  double m_fx, m_fy;

  mutable std::mutex m_mutex;             ///< guards everything below except m_thread
  std::condition_variable m_wake;
  std::deque<TSmootherFrame> m_queue;     ///< frames handed over, not yet ingested
  bool m_stop = false, m_finished = false;
  std::vector<core::TStampedPose> m_framePoses;  ///< the filter's pose of every ingested frame
  std::vector<std::size_t> m_frameKeyframe;      ///< index into m_keyframes (or npos: none yet)
  std::vector<TKeyframe> m_keyframes;
  std::size_t m_given = 0;                ///< frames given to addFrame()
  TSmootherStats m_stats;
  std::thread m_thread;
};
}  // namespace immslam::refine
