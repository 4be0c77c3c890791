/* Issue 8, bad input: every damaged or malformed input gives a clear error naming the file, line or
 * key (exit status 1), or is skipped and counted where the issue says so, and the outputs written
 * before the problem stay. Inputs are rendered (handheld.ini, 40 frames) and damaged under
 * build/test-out/robustness/; nothing here needs ../shared/data. */
#include "robustness_helpers.h"

#include <immslam/camera/CCameraModel.h>
#include <immslam/camera/mrpt_camera.h>
#include <immslam/core/config.h>
#include <immslam/io/CRawlogSource.h>

#include <mrpt/core/Clock.h>
#include <mrpt/img/CImage.h>
#include <mrpt/img/TCamera.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationIMU.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/serialization/CArchive.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <random>

#include <unistd.h>

using namespace immslam;
using namespace immslam::robust;

namespace
{
const std::string kSingle = src("ini/single.ini");
const std::string kImm7 = src("ini/imm7.ini");

bool contains(const std::string& s, const std::string& what) { return s.find(what) != std::string::npos; }

/** Writes a rawlog by hand: for each of the first n frames of the base dataset, the image
 * (embedded, with the calibration in cameraParams) unless images == false, and `others` extra
 * non-image observations (odometry, IMU, comment in turn). */
std::string writeMixedRawlog(const std::string& path, int n, bool images, int others)
{
  const auto lines = readRgb(baseDataset());
  const auto cam = camera::loadCalibFile(baseDataset() + "/calib.txt");
  const auto tcam = camera::toTCamera(*cam);
  mrpt::io::CFileGZOutputStream f(path);
  auto a = mrpt::serialization::archiveFrom(f);
  for (int i = 0; i < n; ++i)
  {
    const double t = std::stod(lines[i].stamp);
    if (images)
    {
      auto img = mrpt::obs::CObservationImage::Create();
      img->sensorLabel = "CAMERA";
      img->timestamp = mrpt::Clock::fromDouble(t);
      img->image = mrpt::img::CImage(cv::imread(baseDataset() + "/" + lines[i].path, cv::IMREAD_GRAYSCALE),
                                     mrpt::img::DEEP_COPY);
      if (tcam) img->cameraParams = *tcam;
      a << *img;
    }
    for (int k = 0; k < others; ++k)
    {
      switch ((i + k) % 3)
      {
        case 0:
        {
          auto o = mrpt::obs::CObservationOdometry::Create();
          o->sensorLabel = "ODOMETRY";
          o->timestamp = mrpt::Clock::fromDouble(t);
          a << *o;
          break;
        }
        case 1:
        {
          auto o = mrpt::obs::CObservationIMU::Create();
          o->sensorLabel = "IMU";
          o->timestamp = mrpt::Clock::fromDouble(t);
          a << *o;
          break;
        }
        default:
        {
          auto o = mrpt::obs::CObservationComment::Create();
          o->text = "frame " + std::to_string(i);
          o->timestamp = mrpt::Clock::fromDouble(t);
          a << *o;
        }
      }
    }
  }
  return path;
}

/** The trajectory of a clean run on the base dataset (reference for "nothing lost"). */
const std::vector<std::string>& referenceTrajectory()
{
  static std::once_flag once;
  static std::vector<std::string> lines;
  std::call_once(once, [] {
    const std::string out = processDir("reference_out");
    const auto r = runApp({kSingle, baseDataset(), "--out", out});
    EXPECT_EQ(r.status, 0) << r.err;
    lines = readLines(out + "/trajectory.txt");
  });
  return lines;
}
}  // namespace

// ------------------------------------------------------------------------------------------------
// Rawlogs
// ------------------------------------------------------------------------------------------------

TEST(RobustRawlog, MissingFileIsAnErrorNamingIt)
{
  const std::string p = freshDir("missing_rawlog") + "/nothing_here.rawlog";
  const auto r = runApp({kSingle, p, "--out", freshDir("missing_rawlog_out")});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, p)) << r.err;
}

TEST(RobustRawlog, NotARawlogIsAnErrorNamingIt)
{
  const std::string d = freshDir("not_a_rawlog");
  const std::string text = d + "/text.rawlog", noise = d + "/noise.rawlog";
  std::ofstream(text) << "# a text file\n1 2 3\n";
  {
    std::ofstream f(noise, std::ios::binary);
    std::mt19937 rng(5);
    for (int i = 0; i < 4096; ++i) f.put(static_cast<char>(rng() & 0xff));
  }
  for (const auto& p : {text, noise})
  {
    const auto r = runApp({kSingle, p, "--out", d + "/out"});
    EXPECT_EQ(r.status, 1) << p;
    EXPECT_TRUE(contains(r.err, p)) << r.err;
    EXPECT_LT(r.err.size(), 2000u) << "error text should be short: " << r.err;
  }
}

TEST(RobustRawlog, UnreadableFileIsAnErrorNamingIt)
{
  if (::geteuid() == 0) GTEST_SKIP() << "running as root: file permissions do not stop reads";
  const std::string d = freshDir("unreadable_rawlog");
  const std::string p = makeRawlog(baseDataset(), d + "/x.rawlog");
  fs::permissions(p, fs::perms::none);
  const auto r = runApp({kSingle, p, "--out", d + "/out"});
  fs::permissions(p, fs::perms::owner_all);
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, p)) << r.err;
}

TEST(RobustRawlog, TruncatedEndsAtTheDamageWithEveryOutputUpToIt)
{
  const auto& ref = referenceTrajectory();
  ASSERT_EQ(ref.size(), 40u);
  const std::string d = freshDir("truncated_rawlog");
  const std::string full = makeRawlog(baseDataset(), d + "/full.rawlog");
  const auto size = fs::file_size(full);
  for (const int percent : {25, 60, 95})
  {
    SCOPED_TRACE(percent);
    const std::string p = d + "/cut" + std::to_string(percent) + ".rawlog";
    fs::copy_file(full, p);
    fs::resize_file(p, size * percent / 100);
    const std::string out = d + "/out" + std::to_string(percent);
    const auto r = runApp({kSingle, p, "--out", out});
    // Ends cleanly: the run stops at the damage and writes every output (map.csv included).
    EXPECT_NE(r.status, 2) << r.err;
    EXPECT_TRUE(contains(r.summary.endReason, "truncated/corrupt")) << r.summary.endReason;
    EXPECT_TRUE(contains(r.summary.endReason, p)) << "the damage report names the file: " << r.summary.endReason;
    const auto o = readAndCheckOutputs(out);
    EXPECT_EQ(o.traj.size(), r.summary.framesProcessed);
    EXPECT_GT(o.traj.size(), 0u);
    EXPECT_LT(o.traj.size(), 40u);
    EXPECT_TRUE(fs::exists(out + "/scene.3Dscene"));
    // Nothing lost: the frames before the damage give exactly the clean run's lines.
    const auto lines = readLines(out + "/trajectory.txt");
    for (std::size_t i = 0; i < lines.size() && i < ref.size(); ++i) EXPECT_EQ(lines[i], ref[i]) << "line " << i + 1;
  }
}

TEST(RobustRawlog, CorruptBytesEndAtTheDamage)
{
  const auto& ref = referenceTrajectory();
  const std::string d = freshDir("corrupt_rawlog");
  const std::string gz = makeRawlog(baseDataset(), d + "/gz.rawlog");
  // The same objects uncompressed (CRawlogSource reads plain rawlogs too).
  const std::string plain = d + "/plain.rawlog";
  ASSERT_EQ(std::system(("gzip -dc '" + gz + "' > '" + plain + "'").c_str()), 0);
  for (const auto& p : {gz, plain})
  {
    SCOPED_TRACE(p);
    {
      std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
      f.seekp(static_cast<std::streamoff>(fs::file_size(p) / 2));
      const std::string junk(200, '\x5a');
      f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
    }
    const std::string out = p + ".out";
    const auto r = runApp({kSingle, p, "--out", out});
    EXPECT_NE(r.status, 2) << r.err;
    const auto o = readAndCheckOutputs(out);
    EXPECT_LT(o.traj.size(), 40u);
    EXPECT_TRUE(contains(r.summary.endReason + r.err, "corrupt")) << r.summary.endReason << r.err;
    const auto lines = readLines(out + "/trajectory.txt");
    // The damaged object may still parse (an image with changed pixels): compare up to the frame
    // before the corrupted bytes, i.e. the first ~40 % of the file.
    for (std::size_t i = 0; i < lines.size() && i < 15; ++i) EXPECT_EQ(lines[i], ref[i]) << "line " << i + 1;
  }
}

// A truncated or corrupted rawlog is a bad input: exit status 1, an error naming the file, and all
// outputs up to the damage.
TEST(RobustRawlog, DamageGivesExitStatusOneAfterWritingOutputs)
{
  const std::string d = freshDir("truncated_rawlog_status");
  const std::string p = makeRawlog(baseDataset(), d + "/x.rawlog");
  fs::resize_file(p, fs::file_size(p) / 2);
  const auto r = runApp({kSingle, p, "--out", d + "/out"});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, p)) << r.err;
  EXPECT_TRUE(fs::exists(d + "/out/map.csv"));
}

TEST(RobustRawlog, OtherObservationTypesAreSkippedAndCounted)
{
  const std::string d = freshDir("mixed_rawlog");
  const std::string p = writeMixedRawlog(d + "/mixed.rawlog", 20, true, 2);
  const auto r = runApp({kSingle, p, "--out", d + "/out"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesProcessed, 20u);
  EXPECT_EQ(r.summary.framesSkipped, 40u);
  EXPECT_EQ(r.summary.framesRead, 60u);
  ASSERT_FALSE(r.summary.skipReasons.empty());
  EXPECT_TRUE(contains(r.summary.skipReasons[0], "CObservation")) << r.summary.skipReasons[0];
  const auto o = readAndCheckOutputs(d + "/out");
  EXPECT_EQ(o.traj.size(), 20u);
}

/** The first n frames of the base dataset as a stereo rig's rawlog: CObservationStereoImages
 * (label BUMBLEBEE: the frame left, its mirror image right) when `asStereo`, else two
 * CObservationImage per frame (labels LEFT: the frame, RIGHT: its mirror image), calibrated. */
std::string writeTwoCameraRawlog(const std::string& path, int n, bool asStereo)
{
  const auto lines = readRgb(baseDataset());
  const auto tcam = camera::toTCamera(*camera::loadCalibFile(baseDataset() + "/calib.txt"));
  mrpt::io::CFileGZOutputStream f(path);
  auto a = mrpt::serialization::archiveFrom(f);
  for (int i = 0; i < n; ++i)
  {
    const double t = std::stod(lines[i].stamp);
    const cv::Mat grey = cv::imread(baseDataset() + "/" + lines[i].path, cv::IMREAD_GRAYSCALE);
    cv::Mat mirror;
    cv::flip(grey, mirror, 1);
    if (asStereo)
    {
      auto st = mrpt::obs::CObservationStereoImages::Create();
      st->sensorLabel = "BUMBLEBEE";
      st->timestamp = mrpt::Clock::fromDouble(t);
      st->imageLeft = mrpt::img::CImage(grey, mrpt::img::DEEP_COPY);
      st->imageRight = mrpt::img::CImage(mirror, mrpt::img::DEEP_COPY);
      st->hasImageRight = true;
      if (tcam) st->leftCamera = st->rightCamera = *tcam;
      a << *st;
      continue;
    }
    for (const bool left : {true, false})
    {
      auto img = mrpt::obs::CObservationImage::Create();
      img->sensorLabel = left ? "LEFT" : "RIGHT";
      img->timestamp = mrpt::Clock::fromDouble(t);
      img->image = mrpt::img::CImage(left ? grey : mirror, mrpt::img::DEEP_COPY);
      if (tcam) img->cameraParams = *tcam;
      a << *img;
    }
  }
  return path;
}

TEST(RobustRawlog, StereoRigRawlogsRunOnOneCamera)
{
  // A stereo rig's rawlog, as MRPT logs it (CObservationStereoImages) or as two monocular sensors: the
  // run uses one camera (the left image; the first sensor, or [input] rawlog_sensor_label), never the
  // two interleaved; the other camera's 40 images are counted, only the first 20 logged.
  const std::string d = freshDir("stereo_rawlog");
  const std::string stereo = writeTwoCameraRawlog(d + "/stereo.rawlog", 40, true);
  const auto r = runApp({kSingle, stereo, "--out", d + "/out_stereo"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesProcessed, 40u);
  EXPECT_EQ(r.summary.framesSkipped, 0u);
  EXPECT_EQ(readAndCheckOutputs(d + "/out_stereo").traj.size(), 40u);

  const std::string two = writeTwoCameraRawlog(d + "/two.rawlog", 40, false);
  const auto first = runApp({kSingle, two, "--out", d + "/out_first"});
  EXPECT_EQ(first.status, 0) << first.err;
  EXPECT_EQ(first.summary.framesProcessed, 40u);
  EXPECT_EQ(first.summary.framesSkipped, 40u);
  ASSERT_EQ(first.summary.skipReasons.size(), 20u);  // the ones logged (the warning names the sensors:
  for (const auto& why : first.summary.skipReasons)  // Rawlog.SeveralCamerasTheFirstOrTheOneChosenBySensorLabel)
    EXPECT_TRUE(contains(why, "image of sensor 'RIGHT' skipped")) << why;
  const auto right = runApp({kSingle, two, "--out", d + "/out_right", "--set", "input.rawlog_sensor_label=RIGHT"});
  EXPECT_EQ(right.status, 0) << right.err;
  EXPECT_EQ(right.summary.framesProcessed, 40u);
  // The RIGHT camera saw the mirror image: its trajectory is not the LEFT one's.
  const auto tl = readAndCheckOutputs(d + "/out_first").traj, tr = readAndCheckOutputs(d + "/out_right").traj;
  ASSERT_EQ(tl.size(), tr.size());
  EXPECT_NE(test::readFile(d + "/out_first/trajectory.txt"), test::readFile(d + "/out_right/trajectory.txt"));
  const auto bad = runApp({kSingle, two, "--out", d + "/out_bad", "--set", "input.rawlog_sensor_label=FRONT"});
  EXPECT_EQ(bad.status, 1);
  EXPECT_TRUE(contains(bad.err, "no image of sensor 'FRONT'")) << bad.err;
}

TEST(RobustRawlog, NoImagesIsAnErrorNamingTheFile)
{
  const std::string d = freshDir("noimage_rawlog");
  const std::string p = writeMixedRawlog(d + "/noimages.rawlog", 10, false, 2);
  for (const bool withCalib : {false, true})
  {
    std::vector<std::string> args{kSingle, p, "--out", d + "/out"};
    if (withCalib) args.insert(args.end(), {"--calib", baseDataset() + "/calib.txt"});
    const auto r = runApp(args);
    EXPECT_EQ(r.status, 1) << "calib " << withCalib;
    EXPECT_TRUE(contains(r.err, p)) << r.err;
    EXPECT_TRUE(contains(r.err, "no image")) << r.err;
  }
}

TEST(RobustRawlog, EmptyIsAnErrorNamingTheFile)
{
  const std::string d = freshDir("empty_rawlog");
  const std::string zero = d + "/zero.rawlog", emptyGz = d + "/emptygz.rawlog";
  std::ofstream(zero).close();
  {
    mrpt::io::CFileGZOutputStream f(emptyGz);  // a valid gzip stream holding no object
  }
  for (const auto& p : {zero, emptyGz})
    for (const bool withCalib : {false, true})
    {
      SCOPED_TRACE(p + (withCalib ? " --calib" : ""));
      std::vector<std::string> args{kSingle, p, "--out", d + "/out"};
      if (withCalib) args.insert(args.end(), {"--calib", baseDataset() + "/calib.txt"});
      const auto r = runApp(args);
      EXPECT_EQ(r.status, 1);
      EXPECT_TRUE(contains(r.err, p)) << r.err;
      EXPECT_TRUE(contains(r.err, "empty")) << r.err;
    }
}

// ------------------------------------------------------------------------------------------------
// Dataset folders
// ------------------------------------------------------------------------------------------------

TEST(RobustDataset, EmptyRgbTxtIsAnErrorNamingIt)
{
  const std::string d = copyBase("empty_rgbtxt");
  for (const std::string content : {"", "# only a comment\n\n   \n"})
  {
    std::ofstream(d + "/rgb.txt") << content;
    const auto r = runApp({kSingle, d, "--out", d + "/out"});
    EXPECT_EQ(r.status, 1);
    EXPECT_TRUE(contains(r.err, d + "/rgb.txt")) << r.err;
  }
}

TEST(RobustDataset, MissingRgbTxtIsAnErrorNamingIt)
{
  const std::string d = copyBase("missing_rgbtxt");
  fs::remove(d + "/rgb.txt");
  const auto r = runApp({kSingle, d, "--out", d + "/out"});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, d + "/rgb.txt")) << r.err;
}

TEST(RobustDataset, MalformedRgbLinesAndMissingFilesAreSkippedAndCounted)
{
  const std::string d = copyBase("malformed_rgbtxt");
  auto lines = readRgb(d);
  ASSERT_EQ(lines.size(), 40u);
  lines[3].stamp = "abc";            // not a number
  lines[5].stamp = "nan";            // not finite
  lines[7].stamp = "1e999";          // overflows
  lines[9].path = "";                // no path
  lines[11].path = "rgb/none.png";   // no such file
  fs::remove(d + "/" + lines[13].path);  // listed, file deleted
  writeRgb(d, lines);
  const auto r = runApp({kSingle, d, "--out", d + "/out"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesRead, 40u);
  EXPECT_EQ(r.summary.framesSkipped, 6u);
  EXPECT_EQ(r.summary.framesProcessed, 34u);
  ASSERT_EQ(r.summary.skipReasons.size(), 6u);
  // rgb.txt line numbers count the header comment: entry k is on line k + 2.
  EXPECT_TRUE(contains(r.summary.skipReasons[0], "rgb.txt:5")) << r.summary.skipReasons[0];
  EXPECT_TRUE(contains(r.summary.skipReasons[1], "rgb.txt:7")) << r.summary.skipReasons[1];
  EXPECT_TRUE(contains(r.summary.skipReasons[2], "rgb.txt:9")) << r.summary.skipReasons[2];
  EXPECT_TRUE(contains(r.summary.skipReasons[3], "rgb.txt:11")) << r.summary.skipReasons[3];
  EXPECT_TRUE(contains(r.summary.skipReasons[4], "rgb/none.png")) << r.summary.skipReasons[4];
  EXPECT_TRUE(contains(r.summary.skipReasons[5], lines[13].path)) << r.summary.skipReasons[5];
  const auto o = readAndCheckOutputs(d + "/out");
  EXPECT_EQ(o.traj.size(), 34u);
}

TEST(RobustDataset, TimestampsThatDoNotAdvanceAreSkippedAndCounted)
{
  // A stamp going back (a clock reset, a hand-edited list) and a repeated one: both frames are skipped
  // with their file named, the frames after them are processed normally (the interval to the next
  // frame is measured from the last processed one, not from the bad stamp), and the time series stay
  // monotonic.
  const std::string d = copyBase("timestamps_backwards");
  auto lines = readRgb(d);
  ASSERT_EQ(lines.size(), 40u);
  lines[17].stamp = "0.1";
  lines[25].stamp = lines[24].stamp;
  writeRgb(d, lines);
  const auto r = runApp({kSingle, d, "--out", d + "/out"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesSkipped, 2u);
  EXPECT_EQ(r.summary.framesProcessed, 38u);
  ASSERT_EQ(r.summary.skipReasons.size(), 2u);
  EXPECT_TRUE(contains(r.summary.skipReasons[0], lines[17].path)) << r.summary.skipReasons[0];
  EXPECT_TRUE(contains(r.summary.skipReasons[0], "not after the previous")) << r.summary.skipReasons[0];
  EXPECT_TRUE(contains(r.summary.skipReasons[1], lines[25].path)) << r.summary.skipReasons[1];
  const auto o = readAndCheckOutputs(d + "/out");
  EXPECT_EQ(o.traj.size(), 38u);
  // The frame after a skipped one comes two periods after the last processed one, as after any dropped
  // frame; none is taken for a long gap in the video (the backward stamp would make it 15 periods).
  const auto stats = readLines(d + "/out/frame_stats.csv");
  ASSERT_GE(stats.size(), 2u);
  const auto header = splitFields(stats[0], ',');
  const auto col = std::find(header.begin(), header.end(), "dt_frames") - header.begin();
  ASSERT_LT(col, static_cast<std::ptrdiff_t>(header.size()));
  for (std::size_t i = 2; i < stats.size(); ++i)
    EXPECT_LE(std::stod(splitFields(stats[i], ',')[static_cast<std::size_t>(col)]), 2.0) << stats[i];
}

TEST(RobustDataset, BlackFirstFramesThenANewFirstMapInTheOutputs)
{
  // The lens cap on for the first 5 frames: the full system starts its map at the first textured frame,
  // straight in SLAM (n_new_first_map), and never again in this run.
  const std::string d = copyBase("black_start");
  const auto lines = readRgb(d);
  for (int k = 0; k < 5; ++k)
  {
    cv::Mat g = cv::imread(d + "/" + lines[k].path, cv::IMREAD_UNCHANGED);
    g.setTo(0);
    cv::imwrite(d + "/" + lines[k].path, g);
  }
  const auto r = runApp({src("ini/imm7-shadow.ini"), d, "--out", d + "/out"});
  ASSERT_EQ(r.status, 0) << r.err;
  readAndCheckOutputs(d + "/out");
  const auto stats = readLines(d + "/out/frame_stats.csv");
  ASSERT_EQ(stats.size(), 41u);
  const auto header = splitFields(stats[0], ',');
  const auto col = std::find(header.begin(), header.end(), "n_new_first_map");
  ASSERT_NE(col, header.end());
  const auto at = static_cast<std::size_t>(col - header.begin());
  for (std::size_t k = 0; k < 40; ++k)
  {
    const int n = std::stoi(splitFields(stats[k + 1], ',').at(at));
    if (k == 5)
      EXPECT_GE(n, 20) << stats[k + 1];
    else
      EXPECT_EQ(n, 0) << "frame " << k;
  }
}

TEST(RobustDataset, UnreadableImagesAreSkippedAndCounted)
{
  const std::string d = copyBase("unreadable_png");
  const auto lines = readRgb(d);
  const auto file = [&](int k) { return d + "/" + lines[k].path; };
  std::ofstream(file(4), std::ios::trunc).close();  // zero bytes
  fs::resize_file(file(8), fs::file_size(file(8)) / 2);  // truncated PNG
  std::ofstream(file(12), std::ios::trunc) << "not a png";  // text
  {
    // PNG signature followed by noise.
    std::ofstream f(file(16), std::ios::binary | std::ios::trunc);
    f << "\x89PNG\r\n\x1a\n";
    std::mt19937 rng(3);
    for (int i = 0; i < 3000; ++i) f.put(static_cast<char>(rng() & 0xff));
  }
  fs::remove(file(20));
  fs::create_directory(file(20));  // a directory where the image should be
  {
    // Not unreadable: 16-bit and RGBA images of the right size are converted and processed.
    cv::Mat g = cv::imread(file(24), cv::IMREAD_GRAYSCALE), g16, rgba;
    g.convertTo(g16, CV_16U, 256.0);
    cv::imwrite(file(24), g16);
    cv::cvtColor(cv::imread(file(28), cv::IMREAD_GRAYSCALE), rgba, cv::COLOR_GRAY2BGRA);
    cv::imwrite(file(28), rgba);
  }
  const auto r = runApp({kSingle, d, "--out", d + "/out"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesSkipped, 5u);
  EXPECT_EQ(r.summary.framesProcessed, 35u);
  ASSERT_EQ(r.summary.skipReasons.size(), 5u);
  const int bad[] = {4, 8, 12, 16, 20};
  for (int i = 0; i < 5; ++i)
    EXPECT_TRUE(contains(r.summary.skipReasons[i], lines[bad[i]].path)) << r.summary.skipReasons[i];
  readAndCheckOutputs(d + "/out");
}

// No frame usable at all: the run processes nothing, which is an error (exit status 1) naming the input.
TEST(RobustDataset, NoUsableFrameGivesExitStatusOne)
{
  const std::string d = copyBase("no_usable_frame");
  for (const auto& l : readRgb(d)) std::ofstream(d + "/" + l.path, std::ios::trunc) << "broken";
  const auto r = runApp({kSingle, d, "--out", d + "/out"});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, d)) << r.err;
}

TEST(RobustDataset, NoUsableFrameEndsWithoutCrashAndEmptyOutputs)
{
  const std::string d = copyBase("no_usable_frame_ok");
  for (const auto& l : readRgb(d)) std::ofstream(d + "/" + l.path, std::ios::trunc) << "broken";
  const auto r = runApp({kSingle, d, "--out", d + "/out"});
  EXPECT_NE(r.status, 2) << r.err;
  EXPECT_EQ(r.summary.framesProcessed, 0u);
  EXPECT_EQ(r.summary.framesSkipped, 40u);
  if (r.status == 0)
  {
    EXPECT_EQ(readAndCheckOutputs(d + "/out").traj.size(), 0u);
  }
}

TEST(RobustDataset, RepeatedAndBackwardTimestampsDoNotBreakTheRun)
{
  const std::string d = copyBase("backward_time");
  auto lines = readRgb(d);
  lines[20].stamp = lines[19].stamp;  // repeated
  lines[30].stamp = lines[25].stamp;  // backwards by 5 frames
  writeRgb(d, lines);
  for (const auto& cfg : {kSingle, kImm7})
  {
    const auto r = runApp({cfg, d, "--out", d + "/out"});
    EXPECT_EQ(r.status, 0) << r.err;
    const auto o = readAndCheckOutputs(d + "/out", true, false);
    EXPECT_EQ(o.traj.size(), r.summary.framesProcessed);
    EXPECT_GE(r.summary.framesProcessed + r.summary.framesSkipped, 40u);
  }
}

// ------------------------------------------------------------------------------------------------
// Image size against the calibration
// ------------------------------------------------------------------------------------------------

TEST(RobustImageSize, MismatchedFramesAreSkippedAndCounted)
{
  const std::string d = copyBase("size_mismatch");
  const auto lines = readRgb(d);
  const auto resize = [&](int k, cv::Size s) {
    cv::Mat m = cv::imread(d + "/" + lines[k].path, cv::IMREAD_UNCHANGED), o;
    cv::resize(m, o, s);
    cv::imwrite(d + "/" + lines[k].path, o);
  };
  resize(10, {160, 120});  // uniform half size: accepted only at the first frame
  resize(11, {160, 120});
  resize(20, {321, 240});
  resize(30, {240, 320});  // transposed
  const auto r = runApp({kSingle, d, "--out", d + "/out"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesSkipped, 4u);
  EXPECT_EQ(r.summary.framesProcessed, 36u);
  ASSERT_EQ(r.summary.skipReasons.size(), 4u);
  EXPECT_TRUE(contains(r.summary.skipReasons[0], "160x120")) << r.summary.skipReasons[0];
  EXPECT_TRUE(contains(r.summary.skipReasons[0], lines[10].path)) << r.summary.skipReasons[0];
  EXPECT_TRUE(contains(r.summary.skipReasons[2], "321x240")) << r.summary.skipReasons[2];
  EXPECT_TRUE(contains(r.summary.skipReasons[3], "does not match the calibration")) << r.summary.skipReasons[3];
  readAndCheckOutputs(d + "/out");
}

TEST(RobustImageSize, UniformRescaleIsAcceptedAtTheFirstFrameOnly)
{
  const std::string d = copyBase("size_uniform");
  const auto lines = readRgb(d);
  for (std::size_t k = 0; k < lines.size(); ++k)
  {
    if (k == 15) continue;  // stays 320x240: no longer matches once the 2x calibration is in use
    cv::Mat m = cv::imread(d + "/" + lines[k].path, cv::IMREAD_UNCHANGED), o;
    cv::resize(m, o, {640, 480}, 0, 0, cv::INTER_LINEAR);
    cv::imwrite(d + "/" + lines[k].path, o);
  }
  const auto r = runApp({kSingle, d, "--out", d + "/out"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesProcessed, 39u);
  EXPECT_EQ(r.summary.framesSkipped, 1u);
  ASSERT_EQ(r.summary.skipReasons.size(), 1u);
  EXPECT_TRUE(contains(r.summary.skipReasons[0], "320x240")) << r.summary.skipReasons[0];
  EXPECT_TRUE(contains(r.summary.skipReasons[0], "640x480")) << r.summary.skipReasons[0];
  readAndCheckOutputs(d + "/out");
}

TEST(RobustImageSize, WideImagesAreProcessedAtAPowerOfTwoReduction)
{
  // 1280x960 images with [input] max_image_width = 1024 are processed at 640x480 with the
  // calibration halved: the same estimate, bit for bit, as the same frames reduced beforehand with a
  // 640x480 calibration. (Each 320x240 pixel is a 4x4 block, so the 2x area reduction is exact.)
  const std::string wide = copyBase("wide_1280"), half = copyBase("wide_640");
  const auto lines = readRgb(wide);
  for (const auto& l : lines)
  {
    const cv::Mat g = cv::imread(wide + "/" + l.path, cv::IMREAD_UNCHANGED);
    cv::Mat w, h;
    cv::resize(g, w, {1280, 960}, 0, 0, cv::INTER_NEAREST);
    cv::resize(w, h, {640, 480}, 0, 0, cv::INTER_AREA);
    cv::imwrite(wide + "/" + l.path, w);
    cv::imwrite(half + "/" + l.path, h);
  }
  const auto base = camera::loadCalibFile(baseDataset() + "/calib.txt");
  camera::saveCalibFile(*base->scaled(4.0), wide + "/calib.txt");
  camera::saveCalibFile(*base->scaled(2.0), half + "/calib.txt");
  const std::vector<std::string> reduce{"--set", "input.max_image_width=1024"};
  const auto with = [&](std::vector<std::string> args) {
    args.insert(args.end(), reduce.begin(), reduce.end());
    return args;
  };
  const auto a = runApp(with({kSingle, wide, "--out", wide + "/out"}));
  const auto b = runApp({kSingle, half, "--out", half + "/out"});
  ASSERT_EQ(a.status, 0) << a.err;
  ASSERT_EQ(b.status, 0) << b.err;
  EXPECT_EQ(a.summary.framesProcessed, 40u);
  EXPECT_EQ(a.summary.framesSkipped, 0u);
  EXPECT_EQ(test::readFile(wide + "/out/trajectory.txt"), test::readFile(half + "/out/trajectory.txt"));
  EXPECT_EQ(test::readFile(wide + "/out/map.csv"), test::readFile(half + "/out/map.csv"));
  readAndCheckOutputs(wide + "/out");
  // 1281x961 (a column and a row of noise added right and bottom: odd sizes such as KITTI's 1241x376):
  // they are dropped before the halving, the same run again.
  const std::string odd = copyBase("wide_1281");
  {
    const auto oc = base->scaled(4.0);
    camera::saveCalibFile(*camera::makeCameraModel(oc->modelName(), 1281, 961, oc->parameters()), odd + "/calib.txt");
  }
  cv::RNG rng(5);
  for (const auto& l : lines)
  {
    cv::Mat w = cv::imread(wide + "/" + l.path, cv::IMREAD_UNCHANGED), o;
    cv::copyMakeBorder(w, o, 0, 1, 0, 1, cv::BORDER_CONSTANT);
    cv::Mat right = o(cv::Rect(1280, 0, 1, 961)), bottom = o(cv::Rect(0, 960, 1281, 1));
    rng.fill(right, cv::RNG::UNIFORM, 0, 255);
    rng.fill(bottom, cv::RNG::UNIFORM, 0, 255);
    cv::imwrite(odd + "/" + l.path, o);
  }
  const auto e = runApp(with({kSingle, odd, "--out", odd + "/out"}));
  ASSERT_EQ(e.status, 0) << e.err;
  EXPECT_EQ(test::readFile(odd + "/out/trajectory.txt"), test::readFile(half + "/out/trajectory.txt"));
  // The default, max_image_width = 0: the full 1280x960 images (a different run).
  const auto c = runApp({kSingle, wide, "--out", wide + "/out_full"});
  ASSERT_EQ(c.status, 0) << c.err;
  EXPECT_EQ(c.summary.framesProcessed, 40u);
  EXPECT_NE(test::readFile(wide + "/out_full/trajectory.txt"), test::readFile(wide + "/out/trajectory.txt"));
}

TEST(RobustImageSize, NonUniformMismatchFromTheStartSkipsEveryFrame)
{
  const std::string d = copyBase("size_nonuniform");
  std::ofstream(d + "/calib.txt") << "pinhole 300 240 240 240 149.5 119.5\n";
  const auto r = runApp({kSingle, d, "--out", d + "/out"});
  EXPECT_NE(r.status, 2) << r.err;
  EXPECT_EQ(r.summary.framesProcessed, 0u);
  EXPECT_EQ(r.summary.framesSkipped, 40u);
}

// ------------------------------------------------------------------------------------------------
// [input] exclusion_masks
// ------------------------------------------------------------------------------------------------

TEST(RobustExclusionMasks, BadFolderWrongSizeAndMissingTimestamps)
{
  // The rendered base folder holds masks/ of a scene without moving objects (all zero): nothing is
  // excluded, the same run bit for bit as without the key.
  const std::string d = copyBase("excl_zero");
  const std::vector<std::string> excl{"--set", "input.exclusion_masks=" + d};
  auto with = [&](std::vector<std::string> a) {
    a.insert(a.end(), excl.begin(), excl.end());
    return a;
  };
  const auto none = runApp({kSingle, d, "--out", d + "/out_none"});
  auto r = runApp(with({kSingle, d, "--out", d + "/out"}));
  ASSERT_EQ(none.status, 0) << none.err;
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesWithoutMask, 0u);
  EXPECT_EQ(test::readFile(d + "/out/trajectory.txt"), test::readFile(d + "/out_none/trajectory.txt"));
  // Timestamps the masks' rgb.txt does not list: those frames exclude nothing, counted in a warning.
  const std::string m = freshDir("excl_partial");
  fs::copy(d + "/masks", m + "/masks");
  {
    const auto lines = readRgb(d);
    std::ofstream o(m + "/rgb.txt");
    for (std::size_t i = 0; i < lines.size(); ++i)
      if (i < 10 || i >= 15) o << lines[i].stamp << " " << lines[i].path << "\n";
  }
  r = runApp({kSingle, d, "--out", d + "/out_partial", "--set", "input.exclusion_masks=" + m});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesWithoutMask, 5u);
  EXPECT_EQ(r.summary.framesProcessed, 40u);
  // A mask of another size than the image: an error naming the frame and the key.
  const auto lines = readRgb(d);
  cv::imwrite(d + "/masks/" + fs::path(lines[3].path).filename().string(), cv::Mat(100, 100, CV_8UC1, cv::Scalar(0)));
  r = runApp(with({kSingle, d, "--out", d + "/out_size"}));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_TRUE(contains(r.err, "[input] exclusion_masks")) << r.err;
  EXPECT_TRUE(contains(r.err, "frame 3")) << r.err;
  EXPECT_TRUE(contains(r.err, "100x100")) << r.err;
  // An unreadable mask: an error naming its file.
  std::ofstream(d + "/masks/" + fs::path(lines[3].path).filename().string()) << "not a png";
  r = runApp(with({kSingle, d, "--out", d + "/out_bad"}));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_TRUE(contains(r.err, fs::path(lines[3].path).filename().string())) << r.err;
  // A folder without masks/: an error naming the key and the folder.
  fs::remove_all(d + "/masks");
  r = runApp(with({kSingle, d, "--out", d + "/out_nomasks"}));
  EXPECT_EQ(r.status, 1) << r.err;
  EXPECT_TRUE(contains(r.err, "[input] exclusion_masks")) << r.err;
  EXPECT_TRUE(contains(r.err, "masks")) << r.err;
}

// ------------------------------------------------------------------------------------------------
// Calibration files
// ------------------------------------------------------------------------------------------------

TEST(RobustCalib, MalformedCalibTxtIsAnErrorNamingFileAndLine)
{
  struct TCase
  {
    std::string content, line, what;
  };
  const std::vector<TCase> cases{
      {"pinhole 320 240 240 abc 159.5 119.5\n", ":1", "fy"},
      {"# comment\npinhole 320 240 240 240 159.5\n", ":2", "needs"},
      {"fishye 320 240 240 240 159.5 119.5\n", ":1", "unknown camera model"},
      {"fisheye 320 240 240 240 159.5 119.5\n", ":1", "needs 10 values"},
      {"pinhole 320 240 -240 240 159.5 119.5\n", ":1", "fx"},
      {"pinhole 0 240 240 240 159.5 119.5\n", ":1", "width"},
      {"pinhole 320.5 240 240 240 159.5 119.5\n", ":1", "width"},
      {"pinhole 320 240 240 240 nan 119.5\n", ":1", "cx"},
      {"pinhole 320 240 240 240 159.5 inf\n", ":1", "cy"},
      {"pinhole 320 240 240 240 159.5 119.5\npinhole 320 240 240 240 159.5 119.5\n", ":2", "second model line"},
      {"", "calib.txt", "no model line"},
      {"# only comments\n\n", "calib.txt", "no model line"},
      {"opencv 320 240 240 240 159.5 119.5 0.1 0.2\n", ":1", "needs"},
      {"davison 320 240 240 240 159.5 119.5 1e-5 7\n", ":1", "needs"},
  };
  const std::string d = copyBase("bad_calib");
  const std::string other = freshDir("bad_calib_arg") + "/my_calib.txt";
  for (const auto& c : cases)
  {
    SCOPED_TRACE(c.content);
    // In the dataset folder...
    std::ofstream(d + "/calib.txt") << c.content;
    auto r = runApp({kSingle, d, "--out", d + "/out"});
    EXPECT_EQ(r.status, 1);
    EXPECT_TRUE(contains(r.err, d + "/calib.txt" + (c.line[0] == ':' ? c.line : ""))) << r.err;
    EXPECT_TRUE(contains(r.err, c.what)) << r.err;
    // ... and given with --calib (overrides the folder's).
    std::ofstream(other) << c.content;
    r = runApp({kSingle, baseDataset(), "--calib", other, "--out", d + "/out"});
    EXPECT_EQ(r.status, 1);
    EXPECT_TRUE(contains(r.err, other + (c.line[0] == ':' ? c.line : ""))) << r.err;
  }
}

TEST(RobustCalib, CalibrationOfTwiceTheImageSizeIsRescaled)
{
  const std::string d = freshDir("calib_2x");
  std::ofstream(d + "/calib.txt") << "pinhole 640 480 480 480 319.5 239.5\n";
  const auto r = runApp({kSingle, baseDataset(), "--calib", d + "/calib.txt", "--out", d + "/out"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesProcessed, 40u);
  readAndCheckOutputs(d + "/out");
}

// ------------------------------------------------------------------------------------------------
// Configuration
// ------------------------------------------------------------------------------------------------

TEST(RobustConfig, UnknownAndMistypedKeysAreNamed)
{
  const std::string d = freshDir("bad_keys");
  struct TCase
  {
    std::string text;
    std::vector<std::string> what;
  };
  const std::vector<TCase> cases{
      {"[slam]\nsigma_pixle = 1\n", {"[slam] sigma_pixle", "did you mean 'sigma_pixel'"}},
      {"[slam]\nSigma_Pixel = 1\n", {"Sigma_Pixel"}},
      {"[imm]\nmodel = general:1\n", {"[imm] model", "models"}},
      {"[slma]\nsigma_pixel = 1\n", {"unknown section [slma]"}},
      {"[slam]\nsigma_pixel = one\n", {"[slam] sigma_pixel", "not a number"}},
      {"[slam]\nsigma_pixel = 1,5\n", {"[slam] sigma_pixel", "not a number"}},
      {"[search]\npatch_half_size = 5.5\n", {"[search] patch_half_size", "not an integer"}},
      {"[slam]\npatch_half_size = 5\n", {"[slam] patch_half_size", "moved to [search] patch_half_size"}},
      {"[system]\nshadow_filter = ture\n", {"[system] shadow_filter", "not a boolean"}},
      {"[imm]\nmodels = general:1 generl:0.5\n", {"[imm] models", "generl"}},
      {"[imm]\nmodels =\n", {"[imm] models"}},
      {"[input]\nsource =\n", {"[input] source"}},
  };
  for (const auto& c : cases)
  {
    SCOPED_TRACE(c.text);
    const std::string cfg = d + "/bad.ini";
    std::ofstream(cfg) << c.text;
    const auto r = runApp({cfg, baseDataset(), "--out", d + "/out"});
    EXPECT_EQ(r.status, 1);
    EXPECT_TRUE(contains(r.err, cfg)) << r.err;
    for (const auto& w : c.what) EXPECT_TRUE(contains(r.err, w)) << r.err;
  }
}

TEST(RobustConfig, NanNegativeAndZeroNoiseAreRejectedNamingTheKey)
{
  const std::string d = freshDir("bad_noise");
  const std::vector<std::pair<std::string, std::string>> cases{
      {"slam.sigma_pixel=nan", "[slam] sigma_pixel"},
      {"slam.sigma_pixel=-1", "[slam] sigma_pixel"},
      {"slam.sigma_pixel=0", "[slam] sigma_pixel"},
      {"slam.sigma_pixel=inf", "[slam] sigma_pixel"},
      {"slam.init_rho_std=-1", "[slam] init_rho_std"},
      {"slam.init_rho_std=nan", "[slam] init_rho_std"},
      {"slam.init_linear_velocity_std_px=-5", "[slam] init_linear_velocity_std_px: removed: internal constant"},
      {"slam.max_sigma_pixel=nan", "[slam] max_sigma_pixel"},
      {"slam.max_sigma_pixel=0.1", "[slam] max_sigma_pixel"},
      {"imm.models=general:nan", "[imm] models"},
      {"imm.models=general:-1", "[imm] models"},
      {"imm.models=general:0", "[imm] models"},
      {"imm.models=rotation:inf", "[imm] models"},
      {"imm.models=general:1e400", "[imm] models"},
      {"imm.transition_stay=0.99", "[imm] transition_stay: removed"},
      {"imm.dormant_below=nan", "[imm] dormant_below"},
      {"imm.dormant_below=-0.1", "[imm] dormant_below"},
      {"imm.general_entry=evidence", "[imm] general_entry: removed"},
      {"imm.models=stationary:0.1 general:1", "[imm] models"},
      {"shadow.sigma_pixel=2", "[shadow] sigma_pixel: removed: both filters use [slam] sigma_pixel"},
      {"slam.min_ncc=0.7", "[slam] min_ncc: moved to [search] min_ncc"},
      {"search.min_ncc=2", "[search] min_ncc"},
      {"search.patch_half_size=1", "[search] patch_half_size"},
      {"imm.shake_px=nan", "[imm] shake_px"},
      {"imm.shake_px=-0.1", "[imm] shake_px"},
      {"imm.probability_floor=1e-4", "[imm] probability_floor: removed: internal constant"},
      {"shadow.alpha=0.01", "[shadow] alpha: removed: internal constant"},
      {"ransac.max_hypotheses=100", "[ransac] max_hypotheses: removed: internal constant"},
      {"shadow.sigma_accel_px=-1", "[shadow] sigma_accel_px"},
      {"imm.prior=[nan 0 0 0 0 0 1]", "[imm] prior"},
      {"imm.prior=[-1 1 1 0 0 0 0]", "[imm] prior"},
      {"system.pending_weight=nan", "[system] pending_weight"},
      {"system.pending_weight=1.5", "[system] pending_weight"},
      {"system.pending_weight=0.5x", "[system] pending_weight"},
      {"system.pending_weight=automatic", "[system] pending_weight"},
  };
  for (const auto& cfg : {kSingle, kImm7})
    for (const auto& [set, what] : cases)
    {
      if (cfg == kSingle && set.rfind("imm.prior", 0) == 0) continue;  // 7 values: only for imm7
      SCOPED_TRACE(cfg + " " + set);
      const auto r = runApp({cfg, baseDataset(), "--set", set, "--out", d + "/out"});
      EXPECT_EQ(r.status, 1);
      EXPECT_TRUE(contains(r.err, what)) << r.err;
      EXPECT_TRUE(contains(r.err, cfg)) << r.err;
      EXPECT_FALSE(fs::exists(d + "/out/trajectory.txt")) << "no output before the config is valid";
    }
}

// A negative prior inverse depth would put every new feature behind the camera: rejected.
TEST(RobustConfig, NegativeInverseDepthPriorIsRejected)
{
  const auto r = runApp({kSingle, baseDataset(), "--set", "slam.init_rho=-1", "--out", freshDir("neg_rho")});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, "[slam] init_rho")) << r.err;
}

TEST(RobustConfig, AbsurdButValidValuesFailCleanlyOrRun)
{
  // Values that pass validation but break the numerics: the run must end with a message naming
  // the frame (status 1) or run; never crash, and every output line written is well formed.
  const std::string d = freshDir("absurd_values");
  for (const std::string set : {"imm.shake_px=100", "imm.models=general:1e300",
                                "slam.sigma_pixel=1e-300", "slam.sigma_pixel=1e5", "slam.init_rho=0",
                                "slam.init_rho=1e300"})
  {
    SCOPED_TRACE(set);
    const std::string out = d + "/" + set.substr(0, set.find('='));
    const auto r = runApp({kImm7, baseDataset(), "--set", set, "--out", out});
    EXPECT_TRUE(r.status == 0 || r.status == 1) << r.status;
    if (r.status == 1)
    {
      EXPECT_TRUE(contains(r.err, "frame ") || contains(r.err, set.substr(0, set.find('.')))) << r.err;
    }
    if (fs::exists(out + "/trajectory.txt"))
    {
      const auto o = readAndCheckOutputs(out, r.status == 0);
      EXPECT_EQ(o.traj.size(), r.summary.framesProcessed);
    }
    std::printf("[ info     ] %s: status %d, %zu frames, %s\n", set.c_str(), r.status, r.summary.framesProcessed,
                r.status ? r.err.substr(r.err.find("error")).c_str() : "ok");
  }
}

TEST(RobustConfig, BrokenConfigFiles)
{
  const std::string d = freshDir("broken_config");
  // Missing, a folder, binary noise: status 1 naming the file.
  {
    const auto r = runApp({d + "/missing.ini", baseDataset(), "--out", d + "/out"});
    EXPECT_EQ(r.status, 1);
    EXPECT_TRUE(contains(r.err, d + "/missing.ini")) << r.err;
  }
  {
    fs::create_directory(d + "/folder.ini");
    const auto r = runApp({d + "/folder.ini", baseDataset(), "--out", d + "/out"});
    EXPECT_EQ(r.status, 1);
    EXPECT_TRUE(contains(r.err, d + "/folder.ini")) << r.err;
  }
  // An empty config is valid: every key at its default.
  {
    std::ofstream(d + "/empty.ini").close();
    const auto r = runApp({d + "/empty.ini", baseDataset(), "--out", d + "/out", "--frames", "10"});
    EXPECT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(readAndCheckOutputs(d + "/out").traj.size(), 10u);
  }
}

// MRPT's ini parser silently drops the lines it cannot parse, so a mistyped line ("sigma_pixel 2"
// without '=', a key before the first [section], binary junk) leaves the key at its default and
// the run goes on. The application checks the text first with core::checkIniSyntax() and refuses
// such lines, naming file and line.
TEST(RobustConfig, MalformedLinesAreErrorsNamingFileAndLine)
{
  const std::string d = freshDir("malformed_lines");
  const std::vector<std::pair<std::string, std::string>> cases{
      {"[slam]\nsigma_pixel 2\n", ":2"},
      {"sigma_pixel = 2\n[slam]\n", ":1"},
      {"[slam]\n= 2\n", ":2"},
      {"[slam]\nsigma_pixel = 2\nsigma_pixel = 3\n", ":3"},
  };
  for (const auto& [text, line] : cases)
  {
    SCOPED_TRACE(text);
    std::ofstream(d + "/bad.ini") << text;
    const auto r = runApp({d + "/bad.ini", baseDataset(), "--out", d + "/out"});
    EXPECT_EQ(r.status, 1);
    EXPECT_TRUE(contains(r.err, d + "/bad.ini" + line)) << r.err;
  }
  std::ofstream f(d + "/noise.ini", std::ios::binary);
  f << "[slam]\n";
  std::mt19937 rng(11);
  for (int i = 0; i < 2000; ++i) f.put(static_cast<char>(rng() & 0xff));
  f.close();
  const auto r = runApp({d + "/noise.ini", baseDataset(), "--out", d + "/out"});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, d + "/noise.ini")) << r.err;
}

TEST(RobustConfig, SyntaxCheckerCatchesWhatMrptDrops)
{
  // What the application would report with core::checkIniSyntax (see the test above).
  const auto errorOf = [](const std::string& text) {
    try
    {
      core::checkIniSyntax(text, "x.ini");
    }
    catch (const std::exception& e)
    {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_TRUE(contains(errorOf("[slam]\nsigma_pixel 2\n"), "x.ini:2"));
  EXPECT_TRUE(contains(errorOf("sigma_pixel = 2\n[slam]\n"), "x.ini:1"));
  EXPECT_TRUE(errorOf(test::readFile(kSingle)).empty());
  EXPECT_TRUE(errorOf(test::readFile(kImm7)).empty());
}

// ------------------------------------------------------------------------------------------------
// The image sources directly (libs/io)
// ------------------------------------------------------------------------------------------------

TEST(RobustIo, ImagelessRawlogsThrowNamingTheFileAndWhatTheyHold)
{
  const std::string d = freshDir("io_imageless");
  const std::string p = writeMixedRawlog(d + "/x.rawlog", 4, false, 3);
  try
  {
    io::CRawlogSource s(p);
    ADD_FAILURE() << "no exception";
  }
  catch (const std::runtime_error& e)
  {
    const std::string m = e.what();
    EXPECT_TRUE(contains(m, p)) << m;
    EXPECT_TRUE(contains(m, "4 mrpt::obs::CObservationOdometry")) << m;
    EXPECT_TRUE(contains(m, "4 mrpt::obs::CObservationIMU")) << m;
  }
  const std::string full = makeRawlog(baseDataset(), d + "/full.rawlog");
  fs::resize_file(full, fs::file_size(full) / 3);
  io::CRawlogSource s(full);
  EXPECT_EQ(s.damage().rfind("rawlog truncated/corrupt after entry ", 0), 0u) << s.damage();
  EXPECT_TRUE(contains(s.damage(), " of " + full + ": ")) << s.damage();
}

// ------------------------------------------------------------------------------------------------
// Outputs
// ------------------------------------------------------------------------------------------------

TEST(RobustOutputs, AFailedRunLeavesThePreviousOutputsAlone)
{
  const std::string d = freshDir("keep_outputs");
  auto r = runApp({kSingle, baseDataset(), "--out", d + "/out", "--frames", "15"});
  ASSERT_EQ(r.status, 0) << r.err;
  const std::string before = test::readFile(d + "/out/trajectory.txt");
  for (const std::vector<std::string>& extra :
       {std::vector<std::string>{"--set", "slam.sigma_pixel=nan"}, {"--set", "slam.bogus=1"},
        {"--calib", d + "/missing_calib.txt"}})
  {
    std::vector<std::string> args{kSingle, baseDataset(), "--out", d + "/out"};
    args.insert(args.end(), extra.begin(), extra.end());
    r = runApp(args);
    EXPECT_EQ(r.status, 1);
    EXPECT_EQ(test::readFile(d + "/out/trajectory.txt"), before);
  }
  r = runApp({kSingle, d + "/missing_input", "--out", d + "/out"});
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(test::readFile(d + "/out/trajectory.txt"), before);
}

TEST(RobustOutputs, OutputFolderThatIsAFileIsAnErrorNamingIt)
{
  const std::string d = freshDir("out_is_file");
  std::ofstream(d + "/taken").close();
  const auto r = runApp({kSingle, baseDataset(), "--out", d + "/taken"});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, d + "/taken")) << r.err;
}

TEST(RobustKnownAssociation, BadFileKindsAndFramesWithoutTracks)
{
  // [input] known_association: the tracks of a caller's own front end (timestamp id kind x y z u v).
  const std::string d = copyBase("known_association");
  const auto lines = readRgb(d);
  const std::string tracks = d + "/tracks.txt";
  {
    // Tracks for every frame but 10-14: a grid of points that stay put (a camera at rest).
    std::ofstream o(tracks);
    o << "# timestamp point_id kind x y z u v\n";
    for (std::size_t i = 0; i < lines.size(); ++i)
      if (i < 10 || i >= 15)
        for (int k = 0; k < 30; ++k)
          o << lines[i].stamp << " " << k << (k % 10 == 0 ? " moving" : " static") << " 0 0 0 " << 20 + 45 * (k % 6)
            << " " << 20 + 45 * (k / 6) << "\n";
  }
  auto r = runApp({kSingle, d, "--out", d + "/out", "--set", "input.known_association=" + tracks});
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.summary.framesProcessed, lines.size());
  EXPECT_EQ(r.summary.framesWithoutTracks, 5u);
  // Only the static tracks: runs too.
  r = runApp({kSingle, d, "--out", d + "/out_static", "--set", "input.known_association=" + tracks, "--set",
              "input.known_association_kinds=static"});
  ASSERT_EQ(r.status, 0) << r.err;
  // A kind that is not one: an error naming the key.
  r = runApp({kSingle, d, "--out", d + "/out_kind", "--set", "input.known_association=" + tracks, "--set",
              "input.known_association_kinds=dynamic"});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, "known_association_kinds")) << r.err;
  // A missing file and a malformed line: errors naming the key, the file and the line.
  r = runApp({kSingle, d, "--out", d + "/out_missing", "--set", "input.known_association=" + d + "/nope.txt"});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, "[input] known_association")) << r.err;
  EXPECT_TRUE(contains(r.err, d + "/nope.txt")) << r.err;
  std::ofstream(tracks, std::ios::app) << lines[3].stamp << " 7 static 0 0 0 12 abc\n";
  r = runApp({kSingle, d, "--out", d + "/out_bad", "--set", "input.known_association=" + tracks});
  EXPECT_EQ(r.status, 1);
  EXPECT_TRUE(contains(r.err, "tracks.txt:")) << r.err;
  EXPECT_FALSE(fs::exists(d + "/out_bad/trajectory.txt"));
}
