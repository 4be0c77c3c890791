/* imm-monoslam — static/dynamic classifier: three uncertain viewing rays (MonoSLAMBOT Sec. III-A). */
#include <immslam/geometry/construction_matrices.h>
#include <immslam/geometry/hypothesis_tests.h>
#include <immslam/geometry/spherical_normalization.h>
#include <immslam/math/chi2.h>
#include <immslam/math/quaternion.h>
#include <immslam/shadow/CRayClassifier.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace immslam::shadow
{
namespace
{
constexpr double kPowerStep = 0.05;  ///< lambda step of the power table
constexpr int kNumDirections = 128;  ///< directions of detectionProbability()
constexpr double kPi = 3.14159265358979323846;
}  // namespace

// ---------------------------------------------------------------------------------------------
// TRayTrack
// ---------------------------------------------------------------------------------------------
void TRayTrack::start(std::int64_t frame_, const Vec2& uv)
{
  views.clear();
  T_0k = TUncertainPose();
  elapsed = 0;
  frame = frame_;
  recent.clear();
  notTranslating = 1;
  acceptStreak = 0;
  evaluations = 0;
  rejections = 0;
  addView(uv);
}

void TRayTrack::advance(std::int64_t frame_, double dt, const Vec3& t, const Vec4& dq, const Mat6& cov,
                        double pNotTranslating)
{
  notTranslating = std::min(notTranslating, std::clamp(pNotTranslating, 0.0, 1.0));
  TUncertainPose inc;
  inc.t = t;
  inc.q = dq;
  inc.cov = cov;
  T_0k = composePoses(T_0k, inc);
  elapsed += dt;
  frame = frame_;
}

void TRayTrack::addView(const Vec2& uv)
{
  TRayView v;
  v.frame = frame;
  v.time = elapsed;
  v.uv = uv;
  v.T_0j = T_0k;
  views.push_back(v);
}

// ---------------------------------------------------------------------------------------------
// Non-central chi-square
// ---------------------------------------------------------------------------------------------
double noncentralChi2Cdf(double x, int dof, double lambda)
{
  if (!(x > 0)) return 0;
  if (lambda <= 0) return math::chi2Cdf(x, dof);
  // Poisson(lambda/2) mixture of chi2(dof + 2j); sum outward from the mode for stability.
  const double mu = 0.5 * lambda;
  const int jMode = static_cast<int>(std::floor(mu));
  const auto weight = [&](int j) { return std::exp(-mu + j * std::log(mu) - std::lgamma(j + 1.0)); };
  double sum = 0;
  for (int j = jMode; j >= 0; --j)
  {
    const double w = weight(j);
    sum += w * math::chi2Cdf(x, dof + 2 * j);
    if (w < 1e-16 && j < jMode) break;
  }
  for (int j = jMode + 1;; ++j)
  {
    const double w = weight(j);
    sum += w * math::chi2Cdf(x, dof + 2 * j);
    if (w < 1e-16) break;
  }
  return std::min(1.0, sum);
}

double noncentralityForPower(double alpha, int dof, double power)
{
  if (!(alpha > 0 && alpha < 1) || !(power > 0 && power < 1) || dof < 1)
    throw std::invalid_argument("shadow::noncentralityForPower: need 0 < alpha, power < 1 and dof >= 1");
  const double thr = math::chi2Quantile(1 - alpha, dof);
  // 1 - F(thr; lambda) increases with lambda: bisect.
  double lo = 0, hi = 1;
  while (1 - noncentralChi2Cdf(thr, dof, hi) < power) hi *= 2;
  for (int i = 0; i < 100; ++i)
  {
    const double mid = 0.5 * (lo + hi);
    if (1 - noncentralChi2Cdf(thr, dof, mid) < power)
      lo = mid;
    else
      hi = mid;
  }
  return 0.5 * (lo + hi);
}

// ---------------------------------------------------------------------------------------------
// CRayClassifier
// ---------------------------------------------------------------------------------------------
CRayClassifier::CRayClassifier(const TRayClassifierParams& p, camera::CCameraModel::Ptr cam)
    : m_p(p), m_cam(std::move(cam))
{
  if (!m_cam) throw std::invalid_argument("shadow::CRayClassifier: null camera model");
  m_lambda0 = noncentralityForPower(m_p.alpha, 3, m_p.staticPower);
  m_medianChi2 = math::chi2Quantile(0.5, 3);
  m_level = geometry::TSignificance::At(m_p.alpha);
  // Power function of the 3-dof test, tabulated up to power 1 - 1e-9.
  const double thr = math::chi2Quantile(1 - m_p.alpha, 3);
  for (int i = 0;; ++i)
  {
    const double pw = 1 - noncentralChi2Cdf(thr, 3, i * kPowerStep);
    m_powerTable.push_back(pw);
    if (pw > 1 - 1e-9) break;
  }
  // Fibonacci points on the half sphere z >= 0 (lambda(V) = lambda(-V)).
  const double golden = kPi * (3 - std::sqrt(5.0));
  for (int i = 0; i < kNumDirections; ++i)
  {
    const double z = (i + 0.5) / kNumDirections;
    const double r = std::sqrt(1 - z * z);
    m_directions.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
}

double CRayClassifier::powerAt(double lambda) const
{
  if (!(lambda > 0)) return m_powerTable.front();
  const double x = lambda / kPowerStep;
  const std::size_t i = static_cast<std::size_t>(x);
  if (i + 1 >= m_powerTable.size()) return m_powerTable.back();
  const double a = x - static_cast<double>(i);
  return (1 - a) * m_powerTable[i] + a * m_powerTable[i + 1];
}

Vec6 CRayClassifier::viewRay(const TRayView& v, Eigen::Matrix<double, 6, 2>* J_L_uv, Mat6* J_L_pose) const
{
  Mat32 J_b_uv;
  const Vec3 b = m_cam->unproject(v.uv, &J_b_uv).unitVector();
  const Mat3 R = v.T_0j.rotation();
  const Vec3 c = v.T_0j.t;
  const Vec3 d = R * b;
  Vec6 L;
  L << d, c.cross(d);
  // L = (d, c x d): dL = (dd, [c]x dd - [d]x dc), dd = R J dUV - R [b]x dtheta.
  const Mat3 Cx = math::skew(c);
  if (J_L_uv)
  {
    const Mat32 J_d_uv = R * J_b_uv;
    J_L_uv->topRows<3>() = J_d_uv;
    J_L_uv->bottomRows<3>() = Cx * J_d_uv;
  }
  if (J_L_pose)
  {
    const Mat3 J_d_th = -R * math::skew(b);
    J_L_pose->setZero();
    J_L_pose->block<3, 3>(0, 3) = J_d_th;
    J_L_pose->block<3, 3>(3, 0) = -math::skew(d);
    J_L_pose->block<3, 3>(3, 3) = Cx * J_d_th;
  }
  return L;
}

TRayTestResult CRayClassifier::test(const TRayTrack& track) const
{
  TRayTestResult r;
  const int n = static_cast<int>(track.views.size());
  if (n < 3) return r;
  // The first view, the current one and the measured view closest in time to halfway between them.
  const int k = n - 1;
  const double half = 0.5 * (track.views[0].time + track.views[k].time);
  int m = 1;
  for (int j = 2; j < k; ++j)
    if (std::abs(track.views[j].time - half) < std::abs(track.views[m].time - half)) m = j;
  r.viewIndex[0] = 0;
  r.viewIndex[1] = m;
  r.viewIndex[2] = k;

  // Noise vector: [uv0 (2), uv_m (2), uv_k (2), pose_m (6), pose_k (6)].
  const TRayView& v0 = track.views[0];
  const TRayView& vm = track.views[m];
  const TRayView& vk = track.views[k];
  Eigen::Matrix<double, 6, 2> Ju0, Jum, Juk;
  Mat6 Jpm, Jpk;
  r.rays[0].L = viewRay(v0, &Ju0, nullptr);
  r.rays[1].L = viewRay(vm, &Jum, &Jpm);
  r.rays[2].L = viewRay(vk, &Juk, &Jpk);

  using Mat18 = Eigen::Matrix<double, 18, 18>;
  Mat18 Jn = Mat18::Zero();
  Jn.block<6, 2>(0, 0) = Ju0;
  Jn.block<6, 2>(6, 2) = Jum;
  Jn.block<6, 6>(6, 6) = Jpm;
  Jn.block<6, 2>(12, 4) = Juk;
  Jn.block<6, 6>(12, 12) = Jpk;
  Mat18 Sn = Mat18::Zero();
  Sn.topLeftCorner<6, 6>() = m_p.sigmaPx * m_p.sigmaPx * Mat6::Identity();
  const Mat6& Pm = vm.T_0j.cov;
  const Mat6 Cross = perturbationTransport(vm.T_0j, vk.T_0j) * Pm;  // Cov(delta_k, delta_m)
  Sn.block<6, 6>(6, 6) = Pm;
  Sn.block<6, 6>(12, 6) = Cross;
  Sn.block<6, 6>(6, 12) = Cross.transpose();
  Sn.block<6, 6>(12, 12) = vk.T_0j.cov;
  const Mat18 C = Jn * Sn * Jn.transpose();
  r.cov_rays = 0.5 * (C + C.transpose());
  for (int i = 0; i < 3; ++i) r.rays[i].cov = r.cov_rays.block<6, 6>(6 * i, 6 * i);

  double widest = 0;
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      widest = std::max(widest, std::atan2(r.rays[a].L.head<3>().cross(r.rays[b].L.head<3>()).norm(),
                                           r.rays[a].L.head<3>().dot(r.rays[b].L.head<3>())));
  r.parallaxRad = widest;
  if (!(widest > 1e-9)) return r;  // identical rays: no test
  r.test = geometry::threeRaysMeet(r.rays[0], r.rays[1], r.rays[2], m_level, &r.cov_rays);
  r.evaluated = r.test.test.valid;
  return r;
}

bool CRayClassifier::velocityNoncentrality(const TRayTrack& track, const TRayTestResult& r, Mat3& A,
                                           double* distK) const
{
  if (!r.evaluated) return false;
  const Vec4 X = r.test.intersection.X;
  if (!X.allFinite() || std::abs(X[3]) < 1e-9 * X.norm()) return false;
  const Vec3 x = X.head<3>() / X[3];
  const TRayView* v[3] = {&track.views[r.viewIndex[0]], &track.views[r.viewIndex[1]],
                          &track.views[r.viewIndex[2]]};
  // The point must be in front of the first and the current camera.
  const Vec3 pk = v[2]->T_0j.rotation().transpose() * (x - v[2]->T_0j.t);
  if (!(x.z() > 0) || !(pk.z() > 0)) return false;
  if (distK) *distK = pk.norm();

  // Exact rays through x with unit directions (the scale of the tested rays' covariance), their
  // Jacobians w.r.t. V (the point at view j is x + V tau_j), and the spherical normalization with
  // the Plücker tangent projection, as in threeRaysMeet.
  const double tau0 = v[0]->time;
  Vec6 l[3];
  Eigen::Matrix<double, 18, 3> J_l_V;
  Eigen::Matrix<double, 18, 18> Jn = Eigen::Matrix<double, 18, 18>::Zero();
  for (int j = 0; j < 3; ++j)
  {
    const Vec3 c = v[j]->T_0j.t;
    const Vec3 D = x - c;
    const double nD = D.norm();
    if (!(nD > 0)) return false;
    const Vec3 d = D / nD;
    Vec6 L;
    L << d, c.cross(d);
    // Chain rule: d(D/|D|)/dV = tau (I - d d^T) / |D|; L = (d, [c]x d).
    const Mat3 J_d_V = (v[j]->time - tau0) * (Mat3::Identity() - d * d.transpose()) / nD;
    Eigen::Matrix<double, 6, 3> J_L_V;
    J_L_V << J_d_V, math::skew(c) * J_d_V;
    Mat6 Js;
    l[j] = geometry::sphericallyNormalized<6>(L, &Js);
    const Vec6 dl = geometry::dualLine(l[j]).normalized();
    const Mat6 Jj = (Mat6::Identity() - dl * dl.transpose()) * Js;
    Jn.block<6, 6>(6 * j, 6 * j) = Jj;
    J_l_V.middleRows<6>(6 * j) = Jj * J_L_V;
  }
  const Eigen::Matrix<double, 18, 18> S = Jn * r.cov_rays * Jn.transpose();
  // The pair with the widest angle, as in threeRaysMeet.
  int i = 0, jj = 1, k = 2;
  double best = -1;
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
    {
      const double sn = l[a].head<3>().cross(l[b].head<3>()).norm() / (l[a].head<3>().norm() * l[b].head<3>().norm());
      if (sn > best)
      {
        best = sn;
        i = a;
        jj = b;
        k = 3 - a - b;
      }
    }
  if (!(best > 1e-12)) return false;
  Eigen::Matrix<double, 5, 6> Ji, Jj, Jk;
  geometry::concurrencyDistance(l[i], l[jj], l[k], l[i].head<3>().cross(l[jj].head<3>()), &Ji, &Jj, &Jk);
  Eigen::Matrix<double, 5, 18> J;
  J.middleCols<6>(6 * i) = Ji;
  J.middleCols<6>(6 * jj) = Jj;
  J.middleCols<6>(6 * k) = Jk;
  const Eigen::Matrix<double, 4, 18> J2 = J.bottomRows<4>();
  const MatX U2 = geometry::dominantEigenvectors(J2 * S * J2.transpose(), 2);
  Eigen::Matrix<double, 3, 18> Jr;
  Jr << J.row(0), U2.transpose() * J2;
  Mat3 Sr = Jr * S * Jr.transpose();
  Sr = (0.5 * (Sr + Sr.transpose())).eval();
  const Mat3 J_dr_V = Jr * J_l_V;
  Eigen::LDLT<Mat3> ldlt(Sr);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) return false;
  A = J_dr_V.transpose() * ldlt.solve(J_dr_V);
  A = (0.5 * (A + A.transpose())).eval();
  return A.allFinite();
}

double CRayClassifier::minimumDetectableVelocityPx(const TRayTrack& track, const TRayTestResult& r) const
{
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Mat3 A;
  double dist = 0;
  if (!velocityNoncentrality(track, r, A, &dist)) return kInf;
  const double lmin = Eigen::SelfAdjointEigenSolver<Mat3>(A, Eigen::EigenvaluesOnly).eigenvalues()[0];
  if (!(lmin > 0)) return kInf;
  return std::sqrt(m_lambda0 / lmin) * m_cam->fx() / dist;
}

double CRayClassifier::detectionProbability(const TRayTrack& track, const TRayTestResult& r, double speedPx) const
{
  Mat3 A;
  double dist = 0;
  if (!velocityNoncentrality(track, r, A, &dist)) return 0;
  const double speed = speedPx * dist / m_cam->fx();  // length per frame
  if (m_p.staticWorstCase)
    return powerAt(speed * speed * Eigen::SelfAdjointEigenSolver<Mat3>(A, Eigen::EigenvaluesOnly).eigenvalues()[0]);
  double sum = 0;
  for (const Vec3& e : m_directions) sum += powerAt(speed * speed * e.dot(A * e));
  return sum / static_cast<double>(m_directions.size());
}

double CRayClassifier::mapScale(const TRayTrack& track, const TRayTestResult& r, const CMapViews& map) const
{
  constexpr std::size_t kMaxMapFeatures = 8, kMinMapFeatures = 5;
  const TRayView* v[3] = {&track.views[static_cast<std::size_t>(r.viewIndex[0])],
                          &track.views[static_cast<std::size_t>(r.viewIndex[1])],
                          &track.views[static_cast<std::size_t>(r.viewIndex[2])]};
  const auto pixels = map.common({v[0]->frame, v[1]->frame, v[2]->frame}, kMaxMapFeatures);
  if (pixels.size() < kMinMapFeatures) return 1.0;
  std::vector<double> T;
  TRayTrack ref;
  ref.views = {*v[0], *v[1], *v[2]};
  for (const auto& uv : pixels)
  {
    for (int j = 0; j < 3; ++j) ref.views[static_cast<std::size_t>(j)].uv = uv[static_cast<std::size_t>(j)];
    const TRayTestResult rr = test(ref);
    if (rr.evaluated && std::isfinite(rr.test.test.T)) T.push_back(rr.test.test.T);
  }
  if (T.size() < kMinMapFeatures) return 1.0;
  std::nth_element(T.begin(), T.begin() + static_cast<std::ptrdiff_t>(T.size() / 2), T.end());
  return std::max(1.0, T[T.size() / 2] / m_medianChi2);
}

EShadowClass CRayClassifier::classify(TRayTrack& track, TDecision* info, TRayTestResult* result,
                                      const CMapViews* map, double staticNotBefore) const
{
  if (track.views.size() < 3 || track.views.back().frame != track.frame ||
      track.elapsed < m_p.minTestFrames)
    return EShadowClass::Pending;
  TRayTestResult r = test(track);
  const TRayView& v0 = track.views.front();
  const TRayView& vm = track.views[static_cast<std::size_t>(r.viewIndex[1])];
  const TRayView& vk = track.views.back();
  r.depthFree = depthFreeTest(*m_cam, v0.uv, {vm.uv, vm.T_0j, vm.time - v0.time}, {vk.uv, vk.T_0j, vk.time - v0.time},
                              perturbationTransport(vm.T_0j, vk.T_0j) * vm.T_0j.cov, m_p.sigmaPx, m_level,
                              m_p.maxInverseDistance);
  const TDepthFreeTest& d = r.depthFree;
  EShadowClass out = EShadowClass::Pending;
  // The depth-free test speaks for a camera that does not translate (weight pi_nt, see the class
  // comment); a translating camera is the three-ray test's, as in MonoSLAMBOT.
  const bool depthFreeActive = d.evaluated && track.notTranslating >= 0.5;
  // A rejection must also stand against the map: the same test of the map's static points over the
  // same three frames sees the same relative-motion error (mapScale).
  bool raysRejected = r.evaluated && r.test.test.rejected();
  if (raysRejected && map) raysRejected = r.test.test.T > mapScale(track, r, *map) * r.test.test.threshold;
  if (r.evaluated || depthFreeActive)
  {
    const bool rejected = raysRejected || (depthFreeActive && d.rejected);
    ++track.evaluations;
    track.rejections += rejected ? 1 : 0;
    track.recent.push_back(rejected ? 1 : 0);
    if (static_cast<int>(track.recent.size()) > m_p.dynamicWindow) track.recent.erase(track.recent.begin());
    track.acceptStreak = rejected ? 0 : track.acceptStreak + 1;
    const int nRej = static_cast<int>(std::count(track.recent.begin(), track.recent.end(), 1));
    if (info) info->testT = r.evaluated ? r.test.test.T : d.T;
    if (nRej >= m_p.dynamicRejections)
      out = EShadowClass::Dynamic;
    else if (!rejected && track.acceptStreak >= m_p.staticAcceptances && track.elapsed >= m_p.staticMinFrames &&
             track.elapsed >= staticNotBefore)
    {
      const double pRays = r.evaluated ? detectionProbability(track, r, m_p.staticMinVelocityPx) : 0.0;
      const double pDepthFree = track.notTranslating * depthFreeDetectionProbability(
                                                           d, m_p.staticMinVelocityPx, m_level, m_p.maxInverseDistance);
      const double pd = std::max(pRays, pDepthFree);
      track.detectionProbability = pd;
      if (pd >= m_p.staticPower)
      {
        out = EShadowClass::Static;
        r.staticByDepthFree = pRays < m_p.staticPower;
        if (info)
        {
          info->minDetectableVelocityPx = r.evaluated ? minimumDetectableVelocityPx(track, r)
                                                      : std::numeric_limits<double>::infinity();
          info->detectionProbability = pd;
        }
      }
    }
  }
  if (result) *result = std::move(r);
  return out;
}
}  // namespace immslam::shadow
