/* imm-monoslam — the MonoSLAMBOT shadow filter: wiring of the per-feature EKF and the static/dynamic
 * classifier (the image search is the caller's). */
#include <immslam/math/quaternion.h>
#include <immslam/shadow/CShadowFilter.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unordered_map>

namespace immslam::shadow
{
namespace
{
double msSince(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
const CShadowFilter::TOptions& checked(const CShadowFilter::TOptions& o)
{
  o.validate("shadow");
  return o;
}
}  // namespace

CShadowFilter::CShadowFilter(const TOptions& opts, camera::CCameraModel::Ptr cam, IdAllocator ids)
    : m_opts(checked(opts)),
      m_cam(cam ? cam : throw std::runtime_error("shadow::CShadowFilter: null camera model")),
      m_classifier(m_opts.classifierParams(), m_cam),
      m_ids(std::move(ids))
{
  m_nextId = kFirstOwnId;
  const double f = m_cam->fx();
  m_sigmaV = m_opts.init_velocity_std_px / f;
  m_sigmaA = m_opts.sigma_accel_px / f;
}

std::size_t CShadowFilter::numPending() const
{
  return static_cast<std::size_t>(std::count_if(m_features.begin(), m_features.end(),
                                                [](const TShadowFeature& f) { return f.cls == EShadowClass::Pending; }));
}

std::size_t CShadowFilter::numDynamic() const { return m_features.size() - numPending(); }

const TShadowFeature* CShadowFilter::feature(std::int64_t id) const
{
  for (const auto& f : m_features)
    if (f.id == id) return &f;
  return nullptr;
}

void CShadowFilter::removeFeatures(const std::vector<std::int64_t>& ids)
{
  m_features.erase(std::remove_if(m_features.begin(), m_features.end(),
                                  [&](const TShadowFeature& f)
                                  { return std::find(ids.begin(), ids.end(), f.id) != ids.end(); }),
                   m_features.end());
}

void CShadowFilter::setMapCopies(const std::vector<std::int64_t>& ids, bool copies)
{
  for (auto& f : m_features)
    if (std::find(ids.begin(), ids.end(), f.id) != ids.end()) f.mapCopy = copies;
}

std::vector<Vec2> CShadowFilter::occupiedPixels() const
{
  std::vector<Vec2> out;
  out.reserve(m_features.size());
  for (const auto& f : m_features) out.push_back(f.measured ? f.uv : f.predicted);
  return out;
}

std::vector<std::int64_t> CShadowFilter::addFeatures(const std::vector<Vec2>& uv)
{
  std::vector<std::int64_t> ids;
  ids.reserve(uv.size());
  for (const Vec2& p : uv)
  {
    if (static_cast<int>(m_features.size()) >= m_opts.max_features || !p.allFinite())
    {
      ids.push_back(-1);
      continue;
    }
    TShadowFeature f;
    f.ekf = initialiseShadowState(*m_cam, p, m_opts.sigma_pixel, m_opts.init_rho, m_opts.init_rho_std, m_sigmaV);
    f.id = m_ids ? m_ids() : m_nextId++;
    f.firstFrame = m_motion.frame;
    f.track.start(m_motion.frame, p);
    f.uv = f.predicted = p;
    f.measured = true;  // observed in the current frame
    f.nMeasured = 1;
    ids.push_back(f.id);
    m_features.push_back(std::move(f));
  }
  return ids;
}

void CShadowFilter::beginFrame(const TCameraMotion& motion)
{
  m_t0 = std::chrono::steady_clock::now();
  if (!(motion.dt > 0) || !motion.t.allFinite() || !motion.dq.allFinite() || !motion.cov_increment.allFinite())
    throw std::runtime_error("shadow::CShadowFilter: invalid camera motion at frame " + std::to_string(motion.frame));
  m_motion = motion;
  m_motion.dq = math::quatNormalized(motion.dq);
  m_report = TShadowReport();
  m_report.timestamp = motion.timestamp;
  m_report.frame = motion.frame;
  m_started = true;
}

void CShadowFilter::predictAll(const TCameraMotion& motion)
{
  const auto t0 = std::chrono::steady_clock::now();
  const Mat6 covInc = 0.5 * (motion.cov_increment + motion.cov_increment.transpose());
  for (auto& f : m_features)
  {
    predictShadowState(f.ekf, motion.dt, motion.t, m_motion.dq, covInc, m_sigmaA);
    f.track.advance(motion.frame, motion.dt, motion.t, m_motion.dq, covInc, motion.pNotTranslating);
    f.age += motion.dt;
    // Without a measured camera motion (TCameraMotion::measured) the views stop (no view, so no test
    // and no decision) and start again at the next measurement of a measured frame (updateFeature).
    if (!motion.measured && f.cls == EShadowClass::Pending) f.restartViews = true;
    f.searched = f.measured = false;
    f.score = 0;
    if (!shadowInnovation(f.ekf, *m_cam, m_opts.sigma_pixel, f.predicted, f.S))
    {
      f.predicted = Vec2::Constant(std::numeric_limits<double>::quiet_NaN());
      f.S = Mat2::Identity();
    }
  }
  m_report.tPredictMs = msSince(t0);
}

void CShadowFilter::updateFeature(TShadowFeature& f, const Vec2& z)
{
  if (!updateShadowState(f.ekf, *m_cam, z, m_opts.sigma_pixel)) return;
  // A feature missed in the frame before (f.missed) was searched again in a grown region, and this
  // match may be another point (its template re-found on a neighbour): the views start again here, as
  // after a camera motion the SLAM did not measure. Views of two points do not meet, so a static
  // point's track that changed points across a miss would look dynamic (doc/shadow.md, "Decision rules").
  if (f.missed > 0 && f.cls == EShadowClass::Pending) f.restartViews = true;
  f.uv = z;
  f.measured = true;
  f.missed = 0;
  ++f.nMeasured;
  if (f.cls == EShadowClass::Pending)
  {
    if (!f.restartViews)
      f.track.addView(z);
    else if (m_motion.measured)
    {
      // The first measurement after a miss or a frame without measured camera motion: the views start
      // again here.
      f.track.start(m_motion.frame, z);
      f.restartViews = false;
    }
  }
  ++m_report.nMeasured;
}

TPromotion CShadowFilter::makePromotion(const TShadowFeature& f, const TRayTestResult& r) const
{
  TPromotion p;
  p.id = f.id;
  p.uv = f.uv;
  // Static triangulation (the classifier's intersection, in C0) seen from the current camera.
  const Vec4 X = r.test.intersection.X;
  if (r.evaluated && !r.staticByDepthFree && X.allFinite() && std::abs(X[3]) > 1e-9 * X.norm())
  {
    Mat3 cov_x;
    const Vec3 x = r.test.intersection.euclidean(&cov_x);
    const Mat3 R = f.track.T_0k.rotation();
    const Vec3 pk = R.transpose() * (x - f.track.T_0k.t);
    const double d = pk.norm();
    if (pk.z() > 0 && d > 0 && cov_x.allFinite())
    {
      // Chain rule: rho = 1/|p_k|, d rho/d p_k = -p_k^T/|p_k|^3, p_k = R^T (x - t).
      const Eigen::RowVector3d J = -pk.transpose() / (d * d * d) * R.transpose();
      p.rho = 1.0 / d;
      p.sigmaRho = std::sqrt(std::max(0.0, double(J * cov_x * J.transpose())));
      p.p_C = pk;
      p.fromTriangulation = true;
      if (std::isfinite(p.sigmaRho) && p.sigmaRho > 0) return p;
    }
  }
  p.rho = f.ekf.x[kW];
  p.sigmaRho = std::sqrt(std::max(f.ekf.P(kW, kW), 0.0));
  p.p_C = shadowPosition(f.ekf, m_opts.min_inverse_distance);
  p.fromTriangulation = false;
  return p;
}

std::vector<TPromotion> CShadowFilter::releaseUnresolved(int maxCount, int minMeasured,
                                                         const std::unordered_set<std::int64_t>& notReleased)
{
  std::vector<std::size_t> idx;
  for (std::size_t i = 0; i < m_features.size(); ++i)
  {
    const auto& f = m_features[i];
    if (f.cls == EShadowClass::Pending && f.measured && f.nMeasured >= minMeasured && f.track.rejections == 0 &&
        !notReleased.count(f.id))
      idx.push_back(i);
  }
  std::stable_sort(idx.begin(), idx.end(),
                   [&](std::size_t a, std::size_t b) { return m_features[a].firstFrame < m_features[b].firstFrame; });
  if (static_cast<int>(idx.size()) > maxCount) idx.resize(static_cast<std::size_t>(std::max(maxCount, 0)));
  std::vector<TPromotion> out;
  std::vector<char> drop(m_features.size(), 0);
  for (std::size_t i : idx)
  {
    out.push_back(makePromotion(m_features[i], TRayTestResult()));
    drop[i] = 1;
  }
  std::vector<TShadowFeature> kept;
  kept.reserve(m_features.size());
  for (std::size_t i = 0; i < m_features.size(); ++i)
    if (!drop[i]) kept.push_back(std::move(m_features[i]));
  m_features = std::move(kept);
  return out;
}

namespace
{
/** Median of the match scores (0 when there is none). */
double medianScore(std::vector<float> scores)
{
  if (scores.empty()) return 0;
  const auto mid = scores.begin() + static_cast<std::ptrdiff_t>(scores.size() / 2);
  std::nth_element(scores.begin(), mid, scores.end());
  return *mid;
}

/** How many of the pixels `uvs` lie within `radius` px of pixel `uv`. */
int countNear(const Vec2& uv, const std::vector<Vec2>& uvs, double radius)
{
  int n = 0;
  for (const auto& d : uvs)
    if ((d - uv).squaredNorm() < radius * radius) ++n;
  return n;
}

/** Whether at least 2 of the dynamic features measured in this frame (`dynamicUv`) lie within `radius`
 * px of pixel `uv` (one dynamic neighbour may be a false decision). A static decision there waits
 * (classifyAndManage): a point that does not move among points of an object seen moving is more likely
 * that object at rest for a while (a turning point, a pause, a person standing) than the background,
 * and the classifier's guarantee (no mover faster than static_min_velocity_px promoted) says nothing
 * about a mover that is momentarily still. */
bool amongDynamic(const Vec2& uv, const std::vector<Vec2>& dynamicUv, double radius)
{
  return countNear(uv, dynamicUv, radius) >= 2;
}

}  // namespace

bool CShadowFilter::followsOnePoint(const TShadowFeature& f) const
{
  return f.scores.empty() || medianScore(f.scores) >= m_opts.min_point_ncc;
}

void CShadowFilter::recordDecision(const TShadowFeature& f, EShadowClass c, TDecision info)
{
  info.id = f.id;
  info.cls = c;
  info.uv = f.uv;
  info.timestamp = m_motion.timestamp;
  info.frame = m_motion.frame;
  info.ageFrames = static_cast<int>(std::lround(f.age));
  m_report.decisions.push_back(info);
}

std::vector<CShadowFilter::TVerdict> CShadowFilter::classifyPending(const std::vector<Vec2>& dynamicUv, double radius,
                                                                    std::vector<Vec2>& dynamicVerdictUv)
{
  // While the camera does not translate (the bank's stationary and rotation families), a static
  // decision waits until the track is still_camera_static_frames long: the depth-free test then has
  // power against slow image motion too (a mover at a turning point or pausing, one moving along its
  // line of sight, whose features were born while it looked still). Waiting costs the map little: SLAM
  // takes the unresolved features it needs and a watched feature decided static is only retired; with
  // translation it would hold back the features SLAM needs.
  const bool notTranslating = m_motion.pNotTranslating >= 0.5;
  const double staticNotBefore = notTranslating ? m_opts.still_camera_static_frames : 0;
  std::vector<TVerdict> verdicts(m_features.size());
  for (std::size_t i = 0; i < m_features.size(); ++i)
  {
    auto& f = m_features[i];  // the classifier keeps its tests' record in the track
    if (f.cls != EShadowClass::Pending || !f.ekf.x.allFinite() || !f.ekf.P.allFinite()) continue;
    auto& v = verdicts[i];
    v.c = m_classifier.classify(f.track, &v.info, &v.r, m_map.empty() ? nullptr : &m_map, staticNotBefore);
    if (v.c == EShadowClass::Static && amongDynamic(f.uv, dynamicUv, radius)) v.c = EShadowClass::Pending;
    if (v.c == EShadowClass::Dynamic) dynamicVerdictUv.push_back(f.uv);
  }
  return verdicts;
}

bool CShadowFilter::decide(TShadowFeature& f, const TVerdict& v, bool othersMove)
{
  if (v.c == EShadowClass::Dynamic)
  {
    f.cls = EShadowClass::Dynamic;
    // Motion seen, but the template follows no point (min_point_ncc): held with no decision.
    f.incoherent = !followsOnePoint(f);
    // Motion seen by this feature alone while the camera translated: held until another one there
    // moves. (A template slides on near 3-D structure through parallax: over a track the camera did
    // not translate, a lone verdict is decided at once.)
    f.lone = !f.incoherent && !f.mapCopy && !m_opts.decide_lone_dynamic && f.track.notTranslating < 0.5 &&
             !othersMove;
    if (f.lone)
    {
      f.incoherent = true;
      f.loneVerdict = v.info;
    }
    f.track.views.clear();
    f.track.views.shrink_to_fit();
    f.scores.clear();
    f.scores.shrink_to_fit();
    ++(f.lone ? m_report.nLone : f.incoherent ? m_report.nIncoherent : m_report.nNewDynamic);
  }
  if (v.c != EShadowClass::Pending && !f.incoherent) recordDecision(f, v.c, v.info);
  if (v.c != EShadowClass::Static) return true;
  m_report.promotions.push_back(makePromotion(f, v.r));
  ++m_report.nPromoted;
  return false;  // leaves the shadow filter
}

bool CShadowFilter::keep(const TShadowFeature& f, bool healthy)
{
  if (f.cls == EShadowClass::Pending)
  {
    if (!healthy || f.missed > m_opts.max_missed_frames)
    {
      ++m_report.nLost;
      return false;
    }
    if (f.age >= m_opts.max_pending_frames)
    {
      ++m_report.nTimedOut;
      return false;
    }
    return true;
  }
  if (!healthy || f.missed > m_opts.dynamic_max_missed_frames)
  {
    ++m_report.nDynamicDropped;
    return false;
  }
  return true;
}

void CShadowFilter::classifyAndManage()
{
  const auto t0 = std::chrono::steady_clock::now();
  // Where the dynamic features measured in this frame are: a static decision waits while the
  // feature is among them (amongDynamic), within a cell of SLAM's default 8 x 6 detection grid.
  const double amongRadius = m_cam->width() / 8.0;
  // The classifier's verdicts first, then the decisions: a dynamic verdict is decided only when
  // another feature within the same radius moves too (one decided dynamic or held alone, measured in
  // this frame: movingUv, or a dynamic verdict of this frame). Alone, the feature is held like an
  // incoherent one (TShadowFeature::lone) and decided once another one there moves: on a static real
  // scene nearly every false dynamic verdict is a lone track that slid along near 3-D structure or low
  // texture (doc/shadow.md, "Decision rules"), while the objects users see move (people, boxes, hands)
  // are seen by several features. A copy of a map feature is decided alone (the map uses it meanwhile).
  std::vector<Vec2> dynamicUv, movingUv, dynamicVerdictUv;
  for (auto& f : m_features)
  {
    if (!f.measured) ++f.missed;
    if (f.cls != EShadowClass::Dynamic || !f.measured) continue;
    dynamicUv.push_back(f.uv);
    if (!f.incoherent || f.lone) movingUv.push_back(f.uv);
  }
  const std::vector<TVerdict> verdicts = classifyPending(dynamicUv, amongRadius, dynamicVerdictUv);
  // Itself among the pixels counted (its verdict or its measurement), so "another one" is 2.
  const auto othersMove = [&](const Vec2& uv)
  { return countNear(uv, movingUv, amongRadius) + countNear(uv, dynamicVerdictUv, amongRadius) >= 2; };
  std::vector<TShadowFeature> kept;
  kept.reserve(m_features.size());
  for (std::size_t i = 0; i < m_features.size(); ++i)
  {
    auto& f = m_features[i];
    const bool healthy = f.ekf.x.allFinite() && f.ekf.P.allFinite();
    if (f.lone && f.measured && healthy && othersMove(f.uv))
    {
      f.lone = f.incoherent = false;
      ++m_report.nNewDynamic;
      ++m_report.nLoneDecided;
      recordDecision(f, EShadowClass::Dynamic, f.loneVerdict);
    }
    // (othersMove only matters to a dynamic verdict.)
    if (f.cls == EShadowClass::Pending && healthy &&
        !decide(f, verdicts[i], verdicts[i].c == EShadowClass::Dynamic && othersMove(f.uv)))
      continue;
    if (keep(f, healthy)) kept.push_back(std::move(f));
  }
  m_features.swap(kept);
  m_report.tClassifyMs = msSince(t0);
}

TTrackPoint CShadowFilter::trackPoint(const TShadowFeature& f) const
{
  TTrackPoint t;
  t.id = f.id;
  Mat3 covC;
  const Vec3 pC = shadowPosition(f.ekf, m_opts.min_inverse_distance, &covC);
  const Mat3 R = math::quatToRotation(m_motion.q_W_C);
  t.p_W = m_motion.r_W_C + R * pC;
  // Chain rule: p_W = r + R Exp(dtheta) p_C -> d p_W = dr - R [p_C]x dtheta.
  Eigen::Matrix<double, 3, 6> Jpose;
  Jpose << Mat3::Identity(), -R * math::skew(pC);
  t.cov_W = R * covC * R.transpose() + Jpose * m_motion.cov_W_C * Jpose.transpose();
  t.v_W = R * shadowVelocity(f.ekf, m_opts.min_inverse_distance);
  t.measured = f.measured;
  t.uv = f.measured ? f.uv : f.predicted;
  t.inverseDistance = f.ekf.x[kW];
  t.distanceRelativeStd =
      std::sqrt(std::max(f.ekf.P(kW, kW), 0.0)) / std::max(f.ekf.x[kW], m_opts.min_inverse_distance);
  return t;
}

void CShadowFilter::endFrame()
{
  for (const auto& f : m_features)
  {
    TFeatureView v;
    v.id = f.id;
    v.cls = f.cls;
    v.predicted = f.predicted;
    v.uv = f.measured ? f.uv : f.predicted;
    v.S = f.S;
    v.searched = f.searched;
    v.measured = f.measured;
    v.score = f.score;  // (0 unless measured in this frame: predictAll)
    v.incoherent = f.incoherent;
    v.ageFrames = static_cast<int>(std::lround(f.age));
    m_report.views.push_back(v);
    if (f.cls == EShadowClass::Dynamic && !f.incoherent)
    {
      m_report.tracks.push_back(trackPoint(f));
      ++m_report.nDynamic;
    }
    else
      ++m_report.nPending;
  }
  m_report.timeMs = msSince(m_t0);
}

void CShadowFilter::predict(const TCameraMotion& motion)
{
  beginFrame(motion);
  predictAll(m_motion);
}

void CShadowFilter::update(const std::vector<TShadowMatch>& matches)
{
  const auto t0 = std::chrono::steady_clock::now();
  std::unordered_map<std::int64_t, std::size_t> index;
  for (std::size_t i = 0; i < m_features.size(); ++i) index.emplace(m_features[i].id, i);
  for (const TShadowMatch& m : matches)
  {
    const auto it = index.find(m.id);
    if (it == index.end()) continue;
    TShadowFeature& f = m_features[it->second];
    if (f.measured) continue;  // one measurement per feature and frame
    f.searched = true;
    ++m_report.nSearched;
    if (m.found && m.uv.allFinite())
    {
      updateFeature(f, m.uv);
      f.score = m.score;
      if (f.cls == EShadowClass::Pending) f.scores.push_back(static_cast<float>(m.score));
    }
  }
  m_report.tUpdateMs += msSince(t0);
}

const TShadowReport& CShadowFilter::finishFrame(double searchMs)
{
  m_report.tSearchMs = searchMs;
  classifyAndManage();
  endFrame();
  return m_report;
}

const TShadowReport& CShadowFilter::processMeasurements(const TCameraMotion& motion,
                                                        const std::vector<std::pair<std::int64_t, Vec2>>& z)
{
  predict(motion);
  std::vector<TShadowMatch> matches;
  matches.reserve(z.size());
  for (const auto& [id, uv] : z)
    if (uv.allFinite()) matches.push_back({id, true, uv});
  update(matches);
  return finishFrame();
}
}  // namespace immslam::shadow
