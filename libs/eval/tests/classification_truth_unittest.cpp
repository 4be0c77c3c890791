/* Tests: static/dynamic decisions against object masks (neighbourhood rule, mask files of a
 * rendered dataset folder) and against projected ground-truth points (nearest point within a
 * radius, unmatched decisions), with hand-counted confusion matrices. */
#include <gtest/gtest.h>
#include <immslam/eval/classification_truth.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>

using namespace immslam;
using namespace immslam::eval;
namespace fs = std::filesystem;

namespace
{
std::string tempPath(const std::string& name)
{
  return (fs::path(::testing::TempDir()) / ("immslam_cls_" + name)).string();
}
void writeText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TClassificationDecision dec(double t, EMotionClass c, double u, double v, std::int64_t id = 0)
{
  TClassificationDecision d;
  d.timestamp = t;
  d.featureId = id;
  d.decided = c;
  d.uv = Vec2(u, v);
  return d;
}
constexpr auto S = EMotionClass::Static;
constexpr auto D = EMotionClass::Dynamic;

void expectMatrix(const TConfusionMatrix& m, size_t ss, size_t sd, size_t ds, size_t dd)
{
  EXPECT_EQ(m.staticAsStatic, ss);
  EXPECT_EQ(m.staticAsDynamic, sd);
  EXPECT_EQ(m.dynamicAsStatic, ds);
  EXPECT_EQ(m.dynamicAsDynamic, dd);
}
}  // namespace

TEST(ClassificationTruth, ReadClassificationsCsv)
{
  const std::string p = tempPath("classes.csv");
  writeText(p, "timestamp,feature_id,class,u,v,extra\n1.000000,7,static,10.5,20.25,x\n\n1.033333,8,dynamic,1,2,y\n");
  const auto d = readClassificationsCsv(p);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_DOUBLE_EQ(d[0].timestamp, 1.0);
  EXPECT_EQ(d[0].featureId, 7);
  EXPECT_EQ(d[0].decided, S);
  EXPECT_EQ(d[0].uv, Vec2(10.5, 20.25));
  EXPECT_EQ(d[1].decided, D);
  const auto expectError = [&](const std::string& text, const std::string& where) {
    writeText(p, text);
    try
    {
      readClassificationsCsv(p);
      ADD_FAILURE() << "no error for " << text;
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_NE(std::string(e.what()).find(p + where), std::string::npos) << e.what();
    }
  };
  expectError("timestamp,feature_id,class,u,v\n1,2,moving,3,4\n", ":2");
  expectError("timestamp,feature_id,class,u,v\n1,2,static,3\n", ":2");
  expectError("timestamp,feature_id,class,u,v\n1,2.5,static,3,4\n", ":2");
  expectError("timestamp,feature_id,klass,u,v\n", ":1");
  EXPECT_THROW(readClassificationsCsv(tempPath("none.csv")), std::runtime_error);
}

TEST(ClassificationTruth, MaskNeighbourhoodRule)
{
  // 10 x 8 mask with a stride of 12 bytes: object pixels (5, 4) and (0, 0).
  std::vector<std::uint8_t> buf(12 * 8, 0);
  buf[4 * 12 + 5] = 3;
  buf[0] = 1;
  buf[11] = 9;  // padding beyond the row: must be ignored
  const TMaskImage m = TMaskImage::fromBuffer(buf.data(), 10, 8, 12);
  ASSERT_EQ(m.pixels.size(), 80u);
  EXPECT_EQ(m.at(5, 4), 3);
  EXPECT_EQ(m.at(9, 0), 0);
  EXPECT_TRUE(m.movingNear(Vec2(5, 4), 0));
  EXPECT_TRUE(m.movingNear(Vec2(5.4, 4.4), 0));   // rounds to (5, 4)
  EXPECT_FALSE(m.movingNear(Vec2(5.6, 4.0), 0));  // rounds to (6, 4)
  EXPECT_TRUE(m.movingNear(Vec2(6, 5), 1));       // (5, 4) is a diagonal neighbour
  EXPECT_FALSE(m.movingNear(Vec2(7, 4), 1));
  EXPECT_TRUE(m.movingNear(Vec2(7, 4), 2));
  EXPECT_FALSE(m.movingNear(Vec2(9, 1), 1));      // (10, 0) is outside the image, not the padding
  EXPECT_TRUE(m.movingNear(Vec2(-1, -1), 1));     // off the image, but (0, 0) is a neighbour
  EXPECT_FALSE(m.movingNear(Vec2(-5, -5), 1));
  EXPECT_FALSE(m.movingNear(Vec2(NAN, 0), 1));
}

TEST(ClassificationTruth, MaskFilesOfARenderedFolder)
{
  const fs::path dir = tempPath("dataset");
  fs::remove_all(dir);
  fs::create_directories(dir / "masks");
  // Two frames of 40 x 30: frame 0 has object 1 in x 10..19, y 5..14; frame 1 object 2 in x 20..29.
  cv::Mat m0(30, 40, CV_8UC1, cv::Scalar(0)), m1(30, 40, CV_8UC1, cv::Scalar(0));
  m0(cv::Rect(10, 5, 10, 10)).setTo(1);
  m1(cv::Rect(20, 5, 10, 10)).setTo(2);
  ASSERT_TRUE(cv::imwrite((dir / "masks" / "000000.png").string(), m0));
  ASSERT_TRUE(cv::imwrite((dir / "masks" / "000001.png").string(), m1));
  writeText((dir / "rgb.txt").string(), "# timestamp filename\n1.000000 rgb/000000.png\n1.033333 rgb/000001.png\n");

  const std::vector<TClassificationDecision> d{
      dec(1.0, D, 12, 7),         // in object 1: dynamic as dynamic
      dec(1.0, S, 9, 7),          // one pixel left of it, neighbour inside: dynamic as static
      dec(1.0, S, 25, 7),         // static as static
      dec(1.033333, D, 12, 7),    // frame 1: object moved away: static as dynamic
      dec(1.033333, D, 30, 14.6), // (30, 15) has (29, 14) as neighbour: dynamic as dynamic
      dec(1.033333, S, 31, 16),   // static as static
      dec(2.0, S, 1, 1)};         // no frame at 2 s: unmatched
  const TClassificationResult r = classificationAgainstMaskFolder(d, dir.string());
  expectMatrix(r.confusion, 2, 1, 1, 2);
  EXPECT_EQ(r.unmatched, 1u);
  EXPECT_NE(r.summary().find("unmatched decisions : 1"), std::string::npos) << r.summary();
  // Radius 0: (9, 7) and (30, 15) are outside the objects (static as static, static as dynamic).
  const TClassificationResult r0 = classificationAgainstMaskFolder(d, dir.string(), 0);
  expectMatrix(r0.confusion, 3, 2, 0, 1);

  // 16-bit and colour masks read as non-zero anywhere.
  cv::Mat m16(4, 5, CV_16UC1, cv::Scalar(0)), mc(4, 5, CV_8UC3, cv::Scalar(0, 0, 0));
  m16.at<std::uint16_t>(2, 3) = 256;  // low byte 0
  mc.at<cv::Vec3b>(1, 1) = cv::Vec3b(0, 0, 7);
  ASSERT_TRUE(cv::imwrite(tempPath("m16.png"), m16));
  ASSERT_TRUE(cv::imwrite(tempPath("mc.png"), mc));
  const TMaskImage a = readMaskImage(tempPath("m16.png")), b = readMaskImage(tempPath("mc.png"));
  EXPECT_EQ(a.width, 5);
  EXPECT_EQ(a.height, 4);
  EXPECT_NE(a.at(3, 2), 0);
  EXPECT_EQ(a.at(2, 2), 0);
  EXPECT_NE(b.at(1, 1), 0);
  EXPECT_EQ(b.at(0, 1), 0);

  // Errors name the file.
  fs::remove(dir / "masks" / "000001.png");
  try
  {
    classificationAgainstMaskFolder(d, dir.string());
    ADD_FAILURE() << "no error for a missing mask";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("000001.png"), std::string::npos) << e.what();
  }
  writeText((dir / "rgb.txt").string(), "1.0 rgb/000000.png\n1.1\n");
  try
  {
    classificationAgainstMaskFolder(d, dir.string());
    ADD_FAILURE() << "no error for a bad rgb.txt";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("rgb.txt:2"), std::string::npos) << e.what();
  }
  fs::remove_all(dir / "masks");
  EXPECT_THROW(classificationAgainstMaskFolder(d, dir.string()), std::runtime_error);
  EXPECT_THROW(classificationAgainstMasks(d, nullptr, -1), std::invalid_argument);
}

TEST(ClassificationTruth, MaskProviderIsCalledOncePerFrame)
{
  int calls = 0;
  const TMaskProvider provider = [&](double t) -> std::optional<TMaskImage> {
    ++calls;
    if (t > 5) return std::nullopt;
    const std::vector<std::uint8_t> px{0, 1, 0, 0};
    return TMaskImage::fromBuffer(px.data(), 2, 2, 2);
  };
  const std::vector<TClassificationDecision> d{dec(1, D, 1, 0), dec(1, D, 0, 1), dec(2, S, 1, 0), dec(9, S, 0, 0)};
  const TClassificationResult r = classificationAgainstMasks(d, provider, 0);
  EXPECT_EQ(calls, 3);
  expectMatrix(r.confusion, 0, 1, 1, 1);
  EXPECT_EQ(r.unmatched, 1u);
}

TEST(ClassificationTruth, NearestGroundTruthPointWithinRadius)
{
  const std::string p = tempPath("points.txt");
  writeText(p,
            "# timestamp point_id kind x y z u v\n"
            "1000.000000 0 static -1.5 2 5.5 100.00 100.00\n"
            "1000.000000 1 moving 3.0 -1.2 5.2 102.00 100.00\n"
            "1000.000000 2 moving 3.0 -1.2 5.2 200.00 50.00\n"
            "1000.066667 0 static -1.5 2 5.5 100.00 101.00\n"
            "1000.066667 1 moving 3.0 -1.2 5.2 150.00 101.00\n");
  const auto pts = readPointsGroundTruth(p);
  ASSERT_EQ(pts.size(), 5u);
  EXPECT_TRUE(pts[1].moving);
  EXPECT_FALSE(pts[0].moving);
  EXPECT_EQ(pts[2].pointId, 2);
  EXPECT_EQ(pts[2].p_W, Vec3(3.0, -1.2, 5.2));
  EXPECT_EQ(pts[2].uv, Vec2(200, 50));

  const std::vector<TClassificationDecision> d{
      dec(1000.0, S, 100.9, 100),       // static point at 0.9 px, moving at 1.1 px: static as static
      dec(1000.0, S, 101.1, 100),       // moving nearer: dynamic as static
      dec(1000.0, D, 200, 52.9),        // 2.9 px from point 2: dynamic as dynamic
      dec(1000.0, D, 200, 53.1),        // 3.1 px: unmatched
      dec(1000.066667, D, 100, 103),    // 2 px from the static point: static as dynamic
      dec(1000.066667, D, 150, 101.0),  // dynamic as dynamic
      dec(1000.5, D, 100, 100)};        // no points at that time: unmatched
  const TClassificationResult r = classificationAgainstPoints(d, pts);
  expectMatrix(r.confusion, 1, 1, 1, 2);
  EXPECT_EQ(r.unmatched, 2u);
  const TClassificationResult r1 = classificationAgainstPoints(d, pts, 1.0);  // 2.9 and 2 px now too far
  expectMatrix(r1.confusion, 1, 0, 1, 1);
  EXPECT_EQ(r1.unmatched, 4u);
  EXPECT_THROW(classificationAgainstPoints(d, pts, -1), std::invalid_argument);

  writeText(p, "1000.0 0 static 1 2 3 4 5\n1000.0 1 flying 1 2 3 4 5\n");
  try
  {
    readPointsGroundTruth(p);
    ADD_FAILURE() << "no error for an unknown kind";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(p + ":2"), std::string::npos) << e.what();
  }
  writeText(p, "1000.0 0 static 1 2 3 4\n");
  EXPECT_THROW(readPointsGroundTruth(p), std::runtime_error);
}

TEST(TrackError, KnownErrorsAfterTheAlignmentAndAssociationByPixel)
{
  // The estimate's world is the ground truth's shrunk by 2, turned 90 deg about z and shifted:
  // S maps it back exactly; the tracked positions carry known errors (in ground-truth units).
  TSim3 S;
  S.s = 2;
  S.R << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  S.t = Vec3(1, -2, 0.5);
  const TSim3 Sinv = S.inverse();
  std::vector<core::TGroundTruthPoint> pts;
  auto gtPoint = [&](double t, std::int64_t id, bool moving, const Vec3& p, double u, double v) {
    core::TGroundTruthPoint g;
    g.timestamp = t, g.pointId = id, g.moving = moving, g.p_W = p, g.uv = Vec2(u, v);
    pts.push_back(g);
  };
  std::vector<core::TTrackSample> tracks;
  auto sample = [&](double t, std::int64_t id, const Vec3& pW_gt, double u, double v) {
    core::TTrackSample s;
    s.timestamp = t, s.featureId = id, s.p_W = Sinv.transform(pW_gt), s.uv = Vec2(u, v);
    tracks.push_back(s);
  };
  for (int k = 0; k < 3; ++k)
  {
    const double t = 10 + k / 15.0;
    gtPoint(t, 1, true, Vec3(k, 1, 5), 100 + 10 * k, 50);
    gtPoint(t, 2, false, Vec3(-1, 0, 4), 200, 120);
    // Track 7 on the moving point, position errors 0.3, 0.4, 0 (x offsets in gt units).
    sample(t, 7, Vec3(k + (k == 0 ? 0.3 : k == 1 ? 0.4 : 0.0), 1, 5), 100 + 10 * k + 1, 50);
  }
  sample(10, 8, Vec3(-1, 0, 4), 201, 121);   // on the static point
  sample(10, 9, Vec3(0, 0, 0), 300, 200);    // far from every point
  sample(99, 9, Vec3(0, 0, 0), 100, 50);     // no ground-truth frame at that time
  const TTrackErrorResult r = trackErrorAgainstPoints(tracks, pts, S);
  EXPECT_EQ(r.samples, 6u);
  EXPECT_EQ(r.tracks, 3u);
  EXPECT_EQ(r.matched, 3u);
  EXPECT_EQ(r.matchedTracks, 1u);
  EXPECT_EQ(r.onStatic, 1u);
  EXPECT_EQ(r.unmatched, 2u);
  EXPECT_NEAR(r.rmse, std::sqrt((0.09 + 0.16) / 3), 1e-12);
  EXPECT_NEAR(r.median, 0.3, 1e-12);
  EXPECT_NEAR(r.max, 0.4, 1e-12);
  EXPECT_NE(r.summary().find("RMS"), std::string::npos);
  // A radius below the 1 px offset leaves the moving rows unmatched.
  EXPECT_EQ(trackErrorAgainstPoints(tracks, pts, S, 0.5).matched, 0u);
  EXPECT_THROW(trackErrorAgainstPoints(tracks, pts, S, -1), std::invalid_argument);
}

TEST(TrackError, ReadsTracksCsvAndNamesBadLines)
{
  const std::string p = tempPath("tracks.csv");
  writeText(p, "timestamp,feature_id,x,y,z,u,v,vx,vy,vz\n1.5,4,0.1,0.2,3,10.5,20,0,0,0\n2,4,0.2,0.2,3,11,20,0,0,0\n");
  const auto t = readTracksCsv(p);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[0].featureId, 4);
  EXPECT_DOUBLE_EQ(t[0].timestamp, 1.5);
  EXPECT_DOUBLE_EQ(t[0].p_W.z(), 3);
  EXPECT_DOUBLE_EQ(t[0].uv.x(), 10.5);
  writeText(p, "timestamp,feature_id,x,y,z,u,v\n1,2,3,x,5,6,7\n");
  try
  {
    readTracksCsv(p);
    FAIL() << "no throw";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(p + ":2"), std::string::npos) << e.what();
  }
  writeText(p, "time,id\n");
  EXPECT_THROW(readTracksCsv(p), std::runtime_error);
  EXPECT_THROW(readTracksCsv(tempPath("missing_tracks.csv")), std::runtime_error);
}
