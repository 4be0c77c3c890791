/* Tests: a pending feature's views belong to one point only while it is followed frame after frame. A
 * feature missed in a frame is searched again in a grown region, and its next match may be another
 * point: a static point whose track lands on a neighbour at another depth must not be decided dynamic
 * because its views before and after the miss are of two points (CShadowFilter::updateFeature). A
 * track that slides off its point without a miss is seen moving alone: it is held until another
 * feature nearby moves (CShadowFilter::TOptions::decide_lone_dynamic). */
#include <gtest/gtest.h>
#include <immslam/shadow/CShadowFilter.h>

#include <array>
#include <cstdio>
#include <map>
#include <optional>

#include "shadow_test_utils.h"

using namespace immslam;
using namespace immslam::shadow;
using namespace immslam::shadow::test;

namespace
{
/** Runs `filter` over the frames of `poses` with known association (exact camera motion, 1 px noise):
 * the features start in frame 0 at the points `pts` that it sees (started(byId) then, byId: id ->
 * index into pts); in frame k feature i is measured at the projection of where(k, i) (std::nullopt:
 * missed) moved by shift(k, i); decided(decision, i) sees each decision. */
template <class Where, class Shift, class Decided, class Started>
void runKnownTracks(CShadowFilter& filter, const camera::CCameraModel& cam, const std::vector<TPose>& poses,
                    const std::vector<Vec3>& pts, Rng& rng, Where where, Shift shift, Decided decided, Started started)
{
  std::map<std::int64_t, std::size_t> byId;
  const Mat6 cov = Mat6::Identity() * 1e-8;
  for (int k = 0; k < static_cast<int>(poses.size()); ++k)
  {
    std::vector<std::pair<std::int64_t, Vec2>> z;
    for (const auto& [id, i] : byId)
    {
      const std::optional<Vec3> p = where(k, i);
      Vec2 uv;
      if (p && cam.project(poses[k].toCamera(*p), uv) && cam.isInImage(uv, 2))
        z.emplace_back(id, uv + shift(k, i) + Vec2(gauss(rng), gauss(rng)));
    }
    for (const auto& d : filter.processMeasurements(pathMotion(poses, k, 30.0, cov), z).decisions)
      decided(d, byId.at(d.id));
    if (k == 0)
    {
      byId = addSeenPoints(filter, cam, poses[0], pts);
      started(byId);
    }
  }
}

/** Static points seen by a hand-held camera (known association, 1 px noise, 120 frames). Every second
 * point is missed in frames 8-9 and from frame 10 on its track follows another static point (the
 * "neighbour": 8 px away in the image at frame 10, at 1.6 times its depth), as a template re-found in
 * a grown search region can. Returns (jumped tracks decided dynamic, decided static; the other tracks
 * decided dynamic, decided static). */
std::array<int, 4> runWithJumps(unsigned seed)
{
  const auto cam = simCamera();
  CShadowFilter::TOptions opts;
  CShadowFilter filter(opts, cam);
  Rng rng(seed);
  const THandheldPath path = randomHandheldPath(rng, 0.01, 120);
  std::vector<TPose> poses(120);
  for (int k = 0; k < 120; ++k) poses[k] = {path.position(k), path.orientation(k)};
  std::vector<Vec3> pts, neighbours;
  while (pts.size() < 30)
  {
    const Vec2 px(uniform(rng, 30, 290), uniform(rng, 30, 210));
    const double depth = uniform(rng, 1.5, 3.0);
    pts.push_back(poses[0].r + poses[0].R() * (cam->unproject(px).unitVector() * depth));
    Vec2 at10;
    if (!cam->project(poses[10].toCamera(pts.back()), at10)) at10 = px;
    const Vec2 shifted = at10 + 8.0 * randomUnit(rng).head<2>().normalized();
    neighbours.push_back(poses[10].r + poses[10].R() * (cam->unproject(shifted).unitVector() * 1.6 * depth));
  }
  std::array<int, 4> out{0, 0, 0, 0};
  runKnownTracks(
      filter, *cam, poses, pts, rng,
      [&](int k, std::size_t i) -> std::optional<Vec3> {
        const bool jumps = i % 2 == 1;
        if (jumps && (k == 8 || k == 9)) return std::nullopt;
        return jumps && k >= 10 ? neighbours[i] : pts[i];
      },
      [](int, std::size_t) { return Vec2::Zero().eval(); },
      [&](const TDecision& d, std::size_t i) { ++out[(i % 2 == 1 ? 0 : 2) + (d.cls == EShadowClass::Dynamic ? 0 : 1)]; },
      [](const std::map<std::int64_t, std::size_t>&) {});
  return out;
}

/** Static points seen by a hand-held camera (known association, 1 px noise, 120 frames), an object of
 * five points 15 px apart moving at about 1 px per frame in the middle of the image, and four static
 * points in the image's corners whose tracks slide off them from frame 5 on (0.5 px per frame in a
 * fixed direction, no miss: a template drifting on near 3-D structure); with slidesAreCopies the
 * slides are copies of map features (CShadowFilter::setMapCopies). Returns (slides decided dynamic,
 * object points decided dynamic, other points decided static, other points decided dynamic). */
std::array<int, 4> runWithSlides(unsigned seed, bool decideLone, bool slidesAreCopies = false)
{
  const auto cam = simCamera();
  CShadowFilter::TOptions opts;
  opts.decide_lone_dynamic = decideLone;
  CShadowFilter filter(opts, cam);
  Rng rng(seed);
  const THandheldPath path = randomHandheldPath(rng, 0.01, 120);
  std::vector<TPose> poses(120);
  for (int k = 0; k < 120; ++k) poses[k] = {path.position(k), path.orientation(k)};
  const auto at = [&](const Vec2& px, double depth) {
    return Vec3(poses[0].r + poses[0].R() * (cam->unproject(px).unitVector() * depth));
  };
  // Kinds: 0 static, 1 sliding track, 2 object.
  std::vector<Vec3> pts;
  std::vector<int> kind;
  std::vector<Vec2> slide;
  for (const Vec2& px : {Vec2(40, 40), Vec2(280, 40), Vec2(40, 200), Vec2(280, 200)})
  {
    pts.push_back(at(px, uniform(rng, 1.5, 3.0)));
    kind.push_back(1);
    slide.push_back(0.5 * randomUnit(rng).head<2>().normalized());
  }
  const Vec3 objectVelocity = 0.008 * randomUnit(rng);
  for (int i = 0; i < 5; ++i)
  {
    pts.push_back(at(Vec2(160 + 15 * (i % 3 - 1), 120 + 15 * (i / 3)), 2.0));
    kind.push_back(2);
    slide.push_back(Vec2::Zero());
  }
  while (pts.size() < 33)
  {
    pts.push_back(at(Vec2(uniform(rng, 30, 290), uniform(rng, 30, 210)), uniform(rng, 1.5, 3.0)));
    kind.push_back(0);
    slide.push_back(Vec2::Zero());
  }
  std::array<int, 4> out{0, 0, 0, 0};
  runKnownTracks(
      filter, *cam, poses, pts, rng,
      [&](int k, std::size_t i) -> std::optional<Vec3> {
        return kind[i] == 2 ? Vec3(pts[i] + k * objectVelocity) : pts[i];
      },
      [&](int k, std::size_t i) { return Vec2(std::max(0, k - 5) * slide[i]); },
      [&](const TDecision& d, std::size_t i) {
        const int kd = kind[i];
        if (d.cls == EShadowClass::Dynamic) ++out[kd == 1 ? 0 : kd == 2 ? 1 : 3];
        else if (kd == 0) ++out[2];
      },
      [&](const std::map<std::int64_t, std::size_t>& byId) {
        std::vector<std::int64_t> slides;
        for (const auto& [id, i] : byId)
          if (kind[i] == 1) slides.push_back(id);
        if (slidesAreCopies) filter.setMapCopies(slides, true);
      });
  return out;
}
}  // namespace

TEST(ShadowFilter, ATrackThatLandsOnAnotherPointAfterAMissIsNotDecidedDynamic)
{
  // Seeds 1-4, 15 jumped and 15 followed tracks each. A track's views start again at its first match
  // after a miss: the jumped tracks are then tracks of their neighbours, decided as static points
  // (0 dynamic, 21 static; their tracks start 10 frames later, so fewer reach the power of a static
  // decision by frame 120). With the views kept across the miss 59 of the 60 were decided dynamic,
  // and their dynamic decisions then held back the static ones near them (15 of the followed tracks
  // decided static instead of 42).
  std::array<int, 4> total{0, 0, 0, 0};
  for (unsigned seed = 1; seed <= 4; ++seed)
  {
    const auto r = runWithJumps(seed);
    for (int i = 0; i < 4; ++i) total[i] += r[i];
  }
  std::printf("[ shadow   ] static tracks that land on a neighbour after a miss: %d dynamic, %d static of 60; "
              "tracks followed throughout: %d dynamic, %d static of 60\n",
              total[0], total[1], total[2], total[3]);
  EXPECT_LE(total[0], 3);   // 5 % of the 60 jumped tracks
  EXPECT_GE(total[1], 15);  // their views started again reach static decisions
  EXPECT_LE(total[2], 3);
  EXPECT_GE(total[3], 35);
}

TEST(ShadowFilter, ATrackThatSlidesOffItsPointAloneIsNotDecidedDynamic)
{
  // Seeds 1-6: 24 sliding tracks, 30 object points. Decided at once (decide_lone_dynamic, the papers'
  // filter) the slides' rays do not meet and nearly all are decided dynamic (measured 23); held until
  // another feature nearby moves (the default) 3 are, where the camera's motion brought another slide
  // or the object near them, while the object's points, which move together, are all decided dynamic
  // as before and the static points static (98 either way). Copies of map features are decided at once
  // (the map uses them while they wait).
  std::array<int, 4> alone{0, 0, 0, 0}, held{0, 0, 0, 0}, copies{0, 0, 0, 0};
  for (unsigned seed = 1; seed <= 6; ++seed)
  {
    const auto a = runWithSlides(seed, true), h = runWithSlides(seed, false), c = runWithSlides(seed, false, true);
    for (int i = 0; i < 4; ++i) alone[i] += a[i], held[i] += h[i], copies[i] += c[i];
  }
  for (const auto& [name, r] : {std::make_pair("decided at once", alone), std::make_pair("held while alone", held),
                                std::make_pair("copies of the map", copies)})
    std::printf("[ shadow   ] %-16s: slides dynamic %d of 24, object points dynamic %d of 30, static points "
                "static %d, other points dynamic %d\n", name, r[0], r[1], r[2], r[3]);
  EXPECT_GE(alone[0], 12) << "the case the rule is for: a slide's rays do not meet";
  EXPECT_LE(held[0], 5);
  EXPECT_GE(held[1], 24);  // object points decided dynamic
  EXPECT_GE(held[1], alone[1] - 2);
  EXPECT_GE(held[2], alone[2] - 2);  // the static decisions are not held back
  EXPECT_EQ(copies[0], alone[0]);
}
