/* imm-monoslam — scripted camera motion (see CCameraTrajectory.h). */
#include <immslam/math/quaternion.h>
#include <immslam/sim/CCameraTrajectory.h>
#include <immslam/sim/CRandom.h>

#include <algorithm>
#include <cmath>

namespace immslam::sim
{
namespace
{
/** C1 ramp from 0 (x <= 0) to 1 (x >= 1): 3x^2 - 2x^3. */
double smoothstep(double x)
{
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  return x * x * (3.0 - 2.0 * x);
}

/** Integral of smoothstep from 0 to x: x^3 - x^4 / 2 (1/2 at x = 1). */
double smoothstepIntegral(double x)
{
  if (x <= 0) return 0;
  if (x >= 1) return 0.5;
  return x * x * x * (1.0 - 0.5 * x);
}

/** Gate of one span at t (0 outside [t0, t1]). */
double gate(double t, double t0, double t1, double in, double out)
{
  if (t < t0 || (out > 0 && t > t1)) return 0.0;
  double g = 1.0;
  if (in > 0) g = std::min(g, smoothstep((t - t0) / in));
  if (out > 0) g = std::min(g, smoothstep((t1 - t) / out));
  return g;
}

/** Integral of the gate over [t0, min(t, t1)] (the ramps do not overlap: in + out <= t1 - t0). */
double gateIntegral(double t, double t0, double t1, double in, double out)
{
  if (t <= t0) return 0.0;
  const double te = out > 0 ? std::min(t, t1) : t;  // the last span's gate continues past t1
  double s = 0;
  // Ramp in.
  if (in > 0)
  {
    s += in * smoothstepIntegral((te - t0) / in);
    if (te <= t0 + in) return s;
  }
  // Plateau.
  const double plateauEnd = out > 0 ? t1 - out : te;
  s += std::min(te, plateauEnd) - (t0 + in);
  if (out <= 0 || te <= plateauEnd) return s;
  // Ramp out: integral of smoothstep((t1 - x) / out) from t1 - out to te.
  return s + out * (0.5 - smoothstepIntegral((t1 - te) / out));
}

/** Right Jacobian of SO(3) at rotation vector e: omega = J_r(e) de/dt for q = exp(e). */
Mat3 rightJacobian(const Vec3& e)
{
  const double th = e.norm();
  const Mat3 K = math::skew(e);
  if (th < 1e-6) return Mat3::Identity() - 0.5 * K + K * K / 6.0;
  return Mat3::Identity() - (1.0 - std::cos(th)) / (th * th) * K + (th - std::sin(th)) / (th * th * th) * K * K;
}
}  // namespace

CCameraTrajectory::CCameraTrajectory(const TScenario& sc) : m_fps(sc.fps)
{
  buildSpans(sc);

  // Hand-held paths, from the camera's own random stream.
  CRandom rng(CRandom::streamSeed(sc.seed, "camera-path"));
  const auto makeSignal = [&](const Vec3& peak, const Vec3& maxRate, TSignal& sig) {
    for (int a = 0; a < 3; ++a)
    {
      // Weights favour the low frequencies (a ~ U(0.3, 1) / f^1.5: velocities ~ f^-0.5), as a
      // hand-held camera wanders slowly and shakes a little; normalized so that sum a = peak.
      auto& axis = sig[static_cast<std::size_t>(a)];
      double sum = 0;
      for (int j = 0; j < sc.n_sinusoids; ++j)
      {
        TSine s;
        const double f = rng.logUniform(sc.freq_hz[0], sc.freq_hz[1]);
        s.amplitude = rng.uniform(0.3, 1.0) * std::pow(sc.freq_hz[0] / f, 1.5);
        s.omega = 2.0 * M_PI * f;
        s.phase = rng.uniform(0.0, 2.0 * M_PI);
        sum += s.amplitude;
        axis.push_back(s);
      }
      for (auto& s : axis) s.amplitude *= peak[a] / sum;
      // Cap the rate: |dx/dtau| <= sum a omega <= maxRate.
      double rate = 0;
      for (const auto& s : axis) rate += s.amplitude * s.omega;
      if (rate > maxRate[a])
        for (auto& s : axis) s.amplitude *= maxRate[a] / rate;
    }
  };
  makeSignal(sc.amplitude_units, sc.max_speed_units_s, m_u);
  makeSignal(sc.amplitude_deg * (M_PI / 180.0), sc.max_rate_deg_s * (M_PI / 180.0), m_e);

  const std::size_t n = sc.frameCount();
  m_poses.reserve(n);
  m_labels.reserve(n);
  double prevV = 0, prevW = 0;
  for (std::size_t k = 0; k < n; ++k)
  {
    const double tk = time(k);
    m_poses.push_back(poseAt(tk));
    const double cv = translationClock(tk), cw = rotationClock(tk);
    m_labels.push_back(k > 0 && cv != prevV   ? EMotionLabel::General
                       : k > 0 && cw != prevW ? EMotionLabel::Rotation
                                              : EMotionLabel::Stationary);
    prevV = cv;
    prevW = cw;
  }
}

void CCameraTrajectory::buildSpans(const TScenario& sc)
{
  // Merge consecutive segments of one type, then place the ramps inside the more-moving segment.
  double t = 0;
  for (const auto& s : sc.segments)
  {
    if (!m_spans.empty() && m_spans.back().type == s.type)
      m_spans.back().t1 = t + s.duration_s;
    else
      m_spans.push_back({s.type, t, t + s.duration_s, 0, 0, 0, 0, 0, 0});
    t += s.duration_s;
  }
  double vClock = 0, wClock = 0;
  for (std::size_t i = 0; i < m_spans.size(); ++i)
  {
    auto& sp = m_spans[i];
    const EMotionLabel prev = i > 0 ? m_spans[i - 1].type : EMotionLabel::Stationary;  // starts at rest
    const bool hasNext = i + 1 < m_spans.size();
    const EMotionLabel next = hasNext ? m_spans[i + 1].type : sp.type;
    const double dur = sp.t1 - sp.t0;
    if (sp.type == EMotionLabel::General)
    {
      const int n = 1 + (hasNext ? 1 : 0);
      sp.vIn = std::min(sc.ramp_s, dur / n);
      sp.vOut = hasNext ? sp.vIn : 0.0;
    }
    if (sp.type != EMotionLabel::Stationary)
    {
      const bool in = prev == EMotionLabel::Stationary, out = hasNext && next == EMotionLabel::Stationary;
      const int n = (in ? 1 : 0) + (out ? 1 : 0);
      const double r = n ? std::min(sc.ramp_s, dur / n) : 0.0;
      sp.wIn = in ? r : 0.0;
      sp.wOut = out ? r : 0.0;
    }
    sp.vClock0 = vClock;
    sp.wClock0 = wClock;
    if (sp.type == EMotionLabel::General) vClock += gateIntegral(sp.t1, sp.t0, sp.t1, sp.vIn, sp.vOut);
    if (sp.type != EMotionLabel::Stationary) wClock += gateIntegral(sp.t1, sp.t0, sp.t1, sp.wIn, sp.wOut);
  }
}

const CCameraTrajectory::TSpan& CCameraTrajectory::spanAt(double t) const
{
  for (const auto& s : m_spans)
    if (t < s.t1) return s;
  return m_spans.back();
}

double CCameraTrajectory::translationGate(double t) const
{
  const auto& s = spanAt(t);
  return s.type == EMotionLabel::General ? gate(t, s.t0, s.t1, s.vIn, s.vOut) : 0.0;
}

double CCameraTrajectory::rotationGate(double t) const
{
  const auto& s = spanAt(t);
  return s.type != EMotionLabel::Stationary ? gate(t, s.t0, s.t1, s.wIn, s.wOut) : 0.0;
}

double CCameraTrajectory::translationClock(double t) const
{
  const auto& s = spanAt(t);
  return s.type == EMotionLabel::General ? s.vClock0 + gateIntegral(t, s.t0, s.t1, s.vIn, s.vOut) : s.vClock0;
}

double CCameraTrajectory::rotationClock(double t) const
{
  const auto& s = spanAt(t);
  return s.type != EMotionLabel::Stationary ? s.wClock0 + gateIntegral(t, s.t0, s.t1, s.wIn, s.wOut) : s.wClock0;
}

void CCameraTrajectory::path(const TSignal& s, double tau, Vec3& x, Vec3* dx)
{
  for (int a = 0; a < 3; ++a)
  {
    double v = 0, dv = 0;
    for (const auto& c : s[static_cast<std::size_t>(a)])
    {
      v += c.amplitude * (std::sin(c.omega * tau + c.phase) - std::sin(c.phase));
      if (dx) dv += c.amplitude * c.omega * std::cos(c.omega * tau + c.phase);
    }
    x[a] = v;
    if (dx) (*dx)[a] = dv;
  }
}

TPose CCameraTrajectory::poseAt(double t) const
{
  TPose p;
  path(m_u, translationClock(t), p.t, nullptr);
  Vec3 e;
  path(m_e, rotationClock(t), e, nullptr);
  p.q = math::quatFromRotationVector(e);
  return p;
}

Vec3 CCameraTrajectory::linearVelocity(double t) const
{
  const double g = translationGate(t);
  if (g == 0.0) return Vec3::Zero();
  Vec3 x, dx;
  path(m_u, translationClock(t), x, &dx);
  return g * dx;
}

Vec3 CCameraTrajectory::angularVelocity(double t) const
{
  const double g = rotationGate(t);
  if (g == 0.0) return Vec3::Zero();
  Vec3 e, de;
  path(m_e, rotationClock(t), e, &de);
  return g * (rightJacobian(e) * de);
}
}  // namespace immslam::sim
