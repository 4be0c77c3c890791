/* Tests: a pending feature's views belong to one point only while it is followed frame after frame. A
 * feature missed in a frame is searched again in a grown region, and its next match may be another
 * point: a static point whose track lands on a neighbour at another depth must not be decided dynamic
 * because its views before and after the miss are of two points (CShadowFilter::updateFeature). */
#include <gtest/gtest.h>
#include <immslam/shadow/CShadowFilter.h>

#include <array>
#include <cstdio>
#include <map>

#include "shadow_test_utils.h"

using namespace immslam;
using namespace immslam::shadow;
using namespace immslam::shadow::test;

namespace
{
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
  std::map<std::int64_t, std::size_t> byId;
  std::array<int, 4> out{0, 0, 0, 0};
  const Mat6 cov = Mat6::Identity() * 1e-8;
  for (int k = 0; k < 120; ++k)
  {
    TCameraMotion m = TCameraMotion::FromPoses(poses[k > 0 ? k - 1 : 0].r, poses[k > 0 ? k - 1 : 0].q, poses[k].r,
                                               poses[k].q);
    m.frame = k;
    m.timestamp = k / 30.0;
    m.cov_increment = cov;
    std::vector<std::pair<std::int64_t, Vec2>> z;
    for (const auto& [id, i] : byId)
    {
      const bool jumps = i % 2 == 1;
      if (jumps && (k == 8 || k == 9)) continue;
      const Vec3& p = jumps && k >= 10 ? neighbours[i] : pts[i];
      Vec2 uv;
      if (cam->project(poses[k].toCamera(p), uv) && cam->isInImage(uv, 2))
        z.emplace_back(id, uv + Vec2(gauss(rng), gauss(rng)));
    }
    const TShadowReport& rep = filter.processMeasurements(m, z);
    for (const auto& d : rep.decisions)
      ++out[(byId.at(d.id) % 2 == 1 ? 0 : 2) + (d.cls == EShadowClass::Dynamic ? 0 : 1)];
    if (k == 0) byId = addSeenPoints(filter, *cam, poses[0], pts);
  }
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
