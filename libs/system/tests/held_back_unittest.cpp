/* Tests: the shadow filter's held-back matches (CHeldBackMatches) go out once their feature is
 * known static, and only then. */
#include <gtest/gtest.h>
#include <immslam/system/CHeldBackMatches.h>

#include <algorithm>

using immslam::Vec2;
using immslam::shadow::EShadowClass;
using immslam::shadow::TShadowReport;
using immslam::system::CHeldBackMatches;
using Ids = std::unordered_set<std::int64_t>;

namespace
{
/** A report in which the features `ids` are pending and measured at (frame, id). */
TShadowReport pending(std::size_t frame, const std::vector<std::int64_t>& ids)
{
  TShadowReport r;
  for (const auto id : ids)
  {
    immslam::shadow::TFeatureView v;
    v.id = id;
    v.cls = EShadowClass::Pending;
    v.measured = true;
    v.uv = Vec2(static_cast<double>(frame), static_cast<double>(id));
    r.views.push_back(v);
  }
  return r;
}

immslam::shadow::TDecision decision(std::int64_t id, EShadowClass cls, std::size_t frame)
{
  immslam::shadow::TDecision d;
  d.id = id;
  d.cls = cls;
  d.uv = Vec2(static_cast<double>(frame), static_cast<double>(id));
  return d;
}

std::size_t countOf(const std::vector<CHeldBackMatches::TMatch>& ms, std::int64_t id)
{
  return static_cast<std::size_t>(std::count_if(ms.begin(), ms.end(), [&](const auto& m) { return m.id == id; }));
}
}  // namespace

TEST(HeldBackMatches, APromotedFeatureGoesOutAfterSlamUsedIt)
{
  // Feature 7 pending over frames 0-9, decided static at frame 10 (promoted: SLAM has it after
  // the frame), then used by SLAM in frames 11-15: its 11 matches go out with frame 15, each with
  // its frame and pixel. Feature 8, promoted too, is deleted by SLAM after 3 updates: nothing.
  CHeldBackMatches hb;
  for (std::size_t f = 0; f < 10; ++f)
  {
    const TShadowReport r = pending(f, {7, 8});
    EXPECT_TRUE(hb.update(f, &r, {}, {}).empty());
  }
  TShadowReport r10;
  r10.decisions = {decision(7, EShadowClass::Static, 10), decision(8, EShadowClass::Static, 10)};
  EXPECT_TRUE(hb.update(10, &r10, {7, 8}, {}).empty());
  for (std::size_t f = 11; f < 15; ++f) EXPECT_TRUE(hb.update(f, nullptr, f < 14 ? Ids{7, 8} : Ids{7}, {7, 8}).empty());
  const auto out = hb.update(15, nullptr, {7}, {7});
  ASSERT_EQ(out.size(), 11u);
  EXPECT_EQ(countOf(out, 8), 0u);
  for (std::size_t f = 0; f <= 10; ++f)
  {
    EXPECT_EQ(out[f].frame, f);
    EXPECT_EQ(out[f].uv, Vec2(static_cast<double>(f), 7.0));
  }
  EXPECT_EQ(hb.held(), 0u);
}

TEST(HeldBackMatches, DynamicLostAndFirstMapCopiesNeverGoOut)
{
  // 1: decided dynamic at frame 5; 2: seen moving (held without a decision, class dynamic); 3: lost
  // (no longer in the views); 4: a first map's probation copy (SLAM measures it itself); 5: a
  // watched feature retired static at frame 6 (never in SLAM): only 5 goes out, at once.
  CHeldBackMatches hb;
  for (std::size_t f = 0; f < 5; ++f)
  {
    const TShadowReport r = pending(f, {1, 2, 3, 4, 5});
    hb.update(f, &r, {4}, {4});
  }
  TShadowReport r5 = pending(5, {5, 4});
  for (const std::int64_t id : {1, 2})
  {
    immslam::shadow::TFeatureView v;
    v.id = id;
    v.cls = EShadowClass::Dynamic;
    v.measured = true;
    r5.views.push_back(v);
  }
  EXPECT_TRUE(hb.update(5, &r5, {4}, {4}).empty());
  TShadowReport r6 = pending(6, {4});
  r6.decisions = {decision(5, EShadowClass::Static, 6), decision(4, EShadowClass::Static, 6)};
  const auto out = hb.update(6, &r6, {4}, {4});
  EXPECT_EQ(out.size(), 7u);  // frames 0-6 of feature 5
  EXPECT_EQ(countOf(out, 5), 7u);
  for (std::size_t f = 7; f < 20; ++f)
  {
    const TShadowReport r = pending(f, {4});
    EXPECT_TRUE(hb.update(f, &r, {4}, {4}).empty());
  }
  EXPECT_EQ(hb.held(), 0u);
}

TEST(HeldBackMatches, AReleasedFeatureGoesOutLikeAPromotedOne)
{
  // Released into SLAM undecided (no decision in the report: it is simply in SLAM after the frame).
  CHeldBackMatches hb;
  for (std::size_t f = 0; f < 12; ++f)
  {
    const TShadowReport r = pending(f, {9});
    hb.update(f, &r, {}, {});
  }
  const TShadowReport r12 = pending(12, {9});
  EXPECT_TRUE(hb.update(12, &r12, {9}, {}).empty());
  std::vector<CHeldBackMatches::TMatch> out;
  for (std::size_t f = 13; f < 13 + CHeldBackMatches::kConfirmUpdates; ++f)
  {
    EXPECT_TRUE(out.empty());
    out = hb.update(f, nullptr, {9}, {9});
  }
  EXPECT_EQ(out.size(), 13u);
}
