/* imm-monoslam — the scripted camera motion of a scenario: segments (stationary, rotation,
 * general) with smooth velocity ramps between them and hand-held-like smooth random motion. */
#pragma once

#include <immslam/sim/TScenario.h>
#include <immslam/sim/types.h>

#include <array>
#include <vector>

namespace immslam::sim
{
/** The camera pose T_W_C as an analytic function of time, with the true motion label of each frame.
 *
 * A hand-held-like path is a sum of `n_sinusoids` sinusoids per axis,
 * \f$ r^*_i(\tau) = \sum_j a_{ij} (\sin(2\pi f_{ij} \tau + \varphi_{ij}) - \sin\varphi_{ij}) \f$ for the
 * optical centre (world axes, peak `amplitude_units`) and likewise \f$ e^*(\tau) \f$ for the rotation
 * vector of the orientation (about the camera's x, y, z at the start, peak `amplitude_deg`), with
 * random frequencies f (log-uniform in `freq_hz`), phases and weights favouring low frequencies
 * (\f$ a \propto U(0.3, 1) / f^{1.5} \f$), deterministic from the seed, scaled down if needed so that
 * the rate bound \f$ \sum_j 2\pi f_{ij} a_{ij} \f$ stays within `max_speed_units_s` (`max_rate_deg_s`);
 * both start at 0.
 *
 * The camera runs along these paths on gated clocks:
 * \f[ r(t) = r^*(\tau_v(t)), \quad q(t) = \exp(e^*(\tau_\omega(t))), \qquad
 *     \tau_v(t) = \int_0^t g_v, \quad \tau_\omega(t) = \int_0^t g_\omega, \f]
 * where the gates \f$g_v, g_\omega \in [0, 1]\f$ come from the script: \f$g_v = 1\f$ in general segments,
 * \f$g_\omega = 1\f$ in rotation and general segments, 0 otherwise, with C1 (smoothstep) ramps of
 * `ramp_s` placed inside the more-moving segment (the sequence starts at rest). Hence the velocities
 * \f$ \dot r = g_v\, r^{*\prime}(\tau_v) \f$ and \f$ \omega = g_\omega\, J_r(e^*)\, e^{*\prime}(\tau_\omega) \f$
 * are continuous, the accelerations bounded, and in a rotation (stationary) segment the clock
 * \f$\tau_v\f$ (and \f$\tau_\omega\f$) is the same constant: the centre (and orientation) is bitwise
 * constant there. Enabling moving objects never changes this path.
 *
 * The label of frame k is the true motion over (t_{k-1}, t_k]: General if the centre moved
 * (\f$\tau_v\f$ advanced), Rotation if only the orientation changed, Stationary otherwise (frame 0:
 * Stationary, the camera starts at rest). */
class CCameraTrajectory
{
 public:
  explicit CCameraTrajectory(const TScenario& sc);

  /** Number of frames. */
  std::size_t size() const { return m_poses.size(); }

  /** Motion time of frame k (s from the first frame). */
  double time(std::size_t k) const { return static_cast<double>(k) / m_fps; }

  /** T_W_C at frame k. */
  const TPose& pose(std::size_t k) const { return m_poses.at(k); }

  /** True motion over (t_{k-1}, t_k]. */
  EMotionLabel label(std::size_t k) const { return m_labels.at(k); }

  /** T_W_C at any motion time t (s from the first frame). */
  TPose poseAt(double t) const;

  /** Linear velocity of the optical centre in W at motion time t (units/s). */
  Vec3 linearVelocity(double t) const;

  /** Angular velocity in the camera frame at motion time t (rad/s). */
  Vec3 angularVelocity(double t) const;

  /** The translation gate \f$g_v(t)\f$ and the rotation gate \f$g_\omega(t)\f$. */
  double translationGate(double t) const;
  double rotationGate(double t) const;

  /** The gated clocks \f$\tau_v(t)\f$ and \f$\tau_\omega(t)\f$ (s). */
  double translationClock(double t) const;
  double rotationClock(double t) const;

 private:
  struct TSine
  {
    double amplitude, omega, phase;
  };
  using TSignal = std::array<std::vector<TSine>, 3>;
  struct TSpan
  {
    EMotionLabel type;
    double t0, t1;
    double vIn, vOut, wIn, wOut;  // ramp lengths (0: none)
    double vClock0, wClock0;      // clocks at t0
  };

  const TSpan& spanAt(double t) const;
  /** m_spans: the scenario's segments, consecutive ones of one type merged, with their ramps placed
   * inside the more-moving segment and the clocks at their starts. */
  void buildSpans(const TScenario& sc);
  /** Path value x(tau) and its derivative dx/dtau. */
  static void path(const TSignal& s, double tau, Vec3& x, Vec3* dx);

  double m_fps;
  std::vector<TSpan> m_spans;
  TSignal m_u, m_e;
  std::vector<TPose> m_poses;
  std::vector<EMotionLabel> m_labels;
};
}  // namespace immslam::sim
