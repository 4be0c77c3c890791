/* imm-monoslam — an online keyframe smoother behind the filter: a sliding window of keyframes, each
 * with the filter's pose and the matches the filter used in its update at that frame, refined by
 * bundleAdjust() in a background thread; every frame's smoothed pose is its keyframe's smoothed
 * pose composed with the filter's motion since that keyframe. The filter never waits for it. */
#pragma once

#include <immslam/core/TTrajectory.h>
#include <immslam/math/types.h>
#include <immslam/refine/bundle_adjust.h>

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

namespace immslam::refine
{
/** One match the filter used in its update: the feature and its measured pixel, undistorted and
 * normalised (x/z, y/z of the camera frame). */
struct TSmootherMatch
{
  std::int64_t featureId = 0;
  Vec2 xn = Vec2::Zero();
  /** The standard deviation of the filter's depth of the feature relative to the depth (and to the
   * camera); infinity: not known (TOptions::startDepthRelSigma). */
  double depthRelSigma = std::numeric_limits<double>::infinity();
};

/** What the smoother receives per frame: the filter's pose T_W_C and the matches of its update. */
struct TSmootherFrame
{
  core::TStampedPose pose;
  std::vector<TSmootherMatch> matches;
  /** Matches of earlier frames (or of this one) that became usable with this frame, with the index
   * of their frame (0 = the first frame given): the measurements of a feature the filter held
   * back until it knew the feature static (the shadow filter's pending features). They take no part
   * in the choice of keyframes, and a feature a frame already measured keeps its match there. */
  std::vector<std::pair<std::size_t, TSmootherMatch>> past;
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
  std::size_t unconverged = 0;     ///< window optimisations that stopped before a convergence tolerance (best step kept)
  std::vector<double> lagFrames;  ///< per optimised keyframe: frames given between its arrival and
                                  ///< its first optimised publication
  double cpuSeconds = 0;          ///< CPU time of the smoother's thread (or of its calls when synchronous)
};

/** Sliding-window keyframe smoother (a fixed-lag bundle adjustment, Triggs et al. 2000, over the
 * filter's own matches, in the manner of a visual odometry's local bundle adjustment).
 *
 * Keyframes: the first frame with at least TOptions::minMatches matches, then every frame whose
 * features shared with the last keyframe moved by TOptions::minParallaxPx (median, once the filter's
 * rotation between the two is taken out), or that shares fewer than minMatches with it (the view is
 * new): a camera at rest or panning adds no keyframe. A new keyframe starts at the last keyframe's
 * smoothed pose composed with the filter's relative motion between the two.
 *
 * Window: the last TOptions::windowKeyframes keyframes (every keyframe so far until a first window
 * has been optimised), and the anchors: up to TOptions::anchorKeyframes keyframes before the window
 * that measured its features, newest first, held at their smoothed poses (they tie the window to the
 * map the windows before placed: its frame and scale, and the features it sees again). Every
 * feature measured by TOptions::minViews of those keyframes is triangulated from the current poses
 * (triangulateAll()), then the window's poses and the points are bundle-adjusted (bundleAdjust(),
 * Huber cost); every TOptions::longWindowEvery keyframes the window is TOptions::longWindowKeyframes
 * long. A window with fewer than two anchors (the run's start, a new map) holds its own gauge:
 * its earliest keyframe that sees the newest with TOptions::gaugeBaselinePx of parallax is held and
 * the distance between the two kept (TBundleOptions::scalePoses); without such a pair it waits.
 * The run's first window also waits for the filter's map to converge (TOptions::startDepthRelSigma):
 * before, the filter may not have seen the camera move, and its motion gives the gauge pair no
 * distance.
 * A keyframe leaving the window keeps its last smoothed pose. Then every frame of the window that is
 * not a keyframe is refined alone against the window's points, held (a motion-only adjustment, run
 * again without the measurements beyond 3 times the frame's median residual).
 *
 * Threads: addFrame() only moves the frame into a queue under a mutex; a worker thread takes the
 * queued frames one by one, picks keyframes and optimises the window at every
 * TOptions::windowEvery-th keyframe (skipped
 * while it is behind by more than TOptions::maxBacklogFrames; the next window then reaches back over
 * the keyframes skipped, up to twice its size; a keyframe no window placed is never an anchor, and a window
 * behind a skipped keyframe it could not reach holds its own gauge). With TOptions::synchronous,
 * addFrame() does that work itself. Both give the same result while the worker keeps up. */
class CKeyframeSmoother
{
 public:
  struct TOptions
  {
    std::size_t windowKeyframes = 20;  ///< keyframes optimised together
    /** The window is optimised at every windowEvery-th keyframe (and at finish()): each keyframe
     * still takes part in about windowKeyframes / windowEvery optimisations, and the smoother's CPU
     * time falls by about that factor (doc/estimator.md). 1: at every keyframe. */
    std::size_t windowEvery = 3;
    /** Keyframes before the window that measured its features, held in its optimisation (newest
     * first): the window continues the map of the windows before it. */
    std::size_t anchorKeyframes = 40;
    /** A frame becomes a keyframe when its features moved this much since the last keyframe once
     * the rotation is taken out (median, pixels): a fraction of the measurement noise, so nearly
     * every frame of a translating camera is one and a camera at rest or panning adds none. */
    double minParallaxPx = 0.25;
    /** The gauge of a window without anchors: a pair of its keyframes with this median parallax
     * (pixels) between them, the older held and the distance kept. */
    double gaugeBaselinePx = 5;
    /** The run's first window waits (up to twice windowKeyframes keyframes) until the filter
     * knows the depths of minMatches of its measurements to this relative standard deviation: the
     * filter has then seen the camera move, and its motion between the gauge pair is a scale (an
     * IMM still in its stationary mode while the camera starts slowly has not moved). 0: no wait. */
    double startDepthRelSigma = 0.1;
    /** Every longWindowEvery keyframes the window reaches back longWindowKeyframes keyframes (a
     * longer fixed lag, run less often): a keyframe that anchors later windows is never moved by
     * them, so a slow drift over a few hundred frames stays in the short windows' poses; a long
     * window spreads it over its span. 0: never. */
    std::size_t longWindowEvery = 100;
    std::size_t longWindowKeyframes = 300;  ///< keyframes of a long window (longWindowEvery)
    /** Iterations of a long window: it starts from the short windows' poses, near its minimum. */
    int longWindowMaxIterations = 5;
    std::size_t minMatches = 8;        ///< a frame with fewer matches is never a keyframe
    int minViews = 3;                  ///< keyframes that must measure a feature for it to enter the window
    double huberPx = 2;                ///< Huber threshold of the cost (pixels)
    int maxIterations = 15;            ///< Levenberg-Marquardt iterations per window optimisation
    /** Iterations of a window with fewer than two anchors (the run's first windows, a new map): its
     * keyframes start from the filter's poses, which at a slow start stay where the filter's
     * stationary mode held them, and the images move them along weakly observed directions (a
     * small sideways translation looks much like a rotation) that take many iterations to follow. */
    int gaugeMaxIterations = 100;
    /** The worker skips the optimisation of a keyframe while more frames than this wait in its
     * queue (a later keyframe's optimisation covers it): the lag stays bounded on a slow machine.
     * While it keeps up, the result is that of a synchronous run. */
    std::size_t maxBacklogFrames = 30;
    /** addFrame() waits while maxBacklogFrames frames are queued instead of letting the worker skip
     * windows: for recorded input, which would otherwise run ahead of the worker; the result is then
     * that of a synchronous run. Never for a live camera (the filter must not wait). */
    bool waitWhenBehind = false;
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
   * \throws std::logic_error after finish(), or for a past match (TSmootherFrame::past) of a frame
   *         after this one. */
  void addFrame(TSmootherFrame frame);

  /** The keyframes as published so far (a copy, safe while the worker runs: for a live scene). */
  std::vector<TSmoothedKeyframe> keyframes() const;

  /** Processes every queued frame, runs the last window optimisation, stops the worker. */
  void finish();

  /** Every frame given, smoothed: a keyframe's smoothed pose; another frame's pose refined against
   * the points of the last window that covered it, or else its keyframe's (the last one at or
   * before it, or the first keyframe) smoothed pose composed with the filter's motion from that
   * keyframe. The filter's poses when there is no keyframe. A frame with fewer than
   * TOptions::minMatches matches (the filter lost its features) between two frames with them takes
   * the pose interpolated in time between theirs (position linear, orientation slerp). Call after
   * finish(). */
  core::TTrajectory trajectory() const;

  /** Lag and CPU time so far. */
  TSmootherStats stats() const;

  /** Whether the filter's depth sigmas (TSmootherMatch::depthRelSigma) are still read: only until
   * the first window has been optimised (TOptions::startDepthRelSigma). The caller can skip
   * computing them afterwards; frames handed over since are never read for them. */
  bool wantsDepths() const { return m_opts.startDepthRelSigma > 0 && !m_optimisedOnce.load(); }

 private:
  void run();
  /** Picks keyframes among `frame`; \return true if it became one. Worker or synchronous caller. */
  bool ingest(TSmootherFrame&& frame);
  /** Takes `frame` in and optimises the window when one is due (TOptions::windowEvery) and the
   * worker is no more than TOptions::maxBacklogFrames behind (`backlog`: frames still queued). */
  void step(TSmootherFrame&& frame, std::size_t backlog);
  /** Per feature frame B (pose, matches) shares with frame A: its bearing change once the filter's
   * rotation between the two is taken out (pixels). */
  std::vector<double> parallaxPx(const core::TStampedPose& poseA, const std::vector<TSmootherMatch>& a,
                                 const core::TStampedPose& poseB, const std::vector<TSmootherMatch>& b) const;
  /** The window's keyframe (index from `first`) held as its gauge: the earliest that sees the
   * newest one with gaugeBaselinePx of parallax; npos if none. */
  std::size_t gaugeKeyframe(std::size_t first, std::size_t n) const;
  /** Measurements of the n keyframes from `first` whose filter depth is known to startDepthRelSigma. */
  std::size_t knownDepths(std::size_t first, std::size_t n) const;
  /** The bundle problem of the window of n keyframes from `first` with its anchors (returned in
   * `anchors`, keyframe indices, newest first; their poses follow the window's). */
  TBundleProblem windowProblem(std::size_t first, std::size_t n, std::vector<std::size_t>& anchors) const;
  /** Frame i's pose from its keyframe (the last one at or before it, or the first keyframe): the
   * keyframe's smoothed pose composed with the filter's motion since; the filter's pose when there
   * is no keyframe. */
  core::TStampedPose composedPose(std::size_t i) const;
  /** Bundle-adjusts the window and publishes its poses. */
  void optimiseWindow();
  /** Every frame from `firstFrame` on that is not a keyframe: its pose refined against the
   * window's points (held), from its keyframe's smoothed pose composed with the filter's motion;
   * then again without the measurements far outside the frame's residual spread. */
  void refineFrames(std::size_t firstFrame, const TBundleProblem& window);

  TOptions m_opts;
  double m_fx, m_fy;

  mutable std::mutex m_mutex;             ///< guards everything below except m_thread
  std::condition_variable m_wake;
  std::condition_variable m_room;         ///< the worker took a frame (TOptions::waitWhenBehind)
  std::deque<TSmootherFrame> m_queue;     ///< frames handed over, not yet ingested
  bool m_stop = false, m_finished = false;
  std::vector<core::TStampedPose> m_framePoses;  ///< the filter's pose of every ingested frame
  std::vector<std::vector<TSmootherMatch>> m_frameMatches;  ///< the matches of every ingested frame
  /** Per frame: its pose refined against the points of the last window that covered it (none for
   * keyframes, and for frames no window has covered yet). */
  std::vector<std::optional<core::TStampedPose>> m_frameRefined;
  std::vector<std::size_t> m_frameKeyframe;      ///< index into m_keyframes (or npos: none yet)
  std::vector<TSmoothedKeyframe> m_keyframes;
  /** Per keyframe: in an optimised window (optimised, or held as its gauge), not yet, or skipped by
   * the worker while behind (and not placed since). */
  std::vector<char> m_placed;
  std::size_t m_given = 0;                ///< frames given to addFrame()
  std::size_t m_longWindowAt = 0;         ///< keyframes there were at the last long window (worker)
  /** Keyframes since the last window optimisation (worker): more than 0, a window is still due. */
  std::size_t m_keyframesSinceWindow = 0;
  TSmootherStats m_stats;
  std::atomic<bool> m_optimisedOnce{false};  ///< m_stats.optimisations > 0 (read without the lock)
  std::thread m_thread;
};
}  // namespace immslam::refine
