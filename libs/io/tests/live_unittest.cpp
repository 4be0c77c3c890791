/* Tests of the live image source (mrpt::hwdrivers::CCameraSensor) without hardware: the image_dir,
 * ffmpeg and rawlog grabbers on files written here, stop requests, opening errors, and the rawlog
 * recorder round trip. Frame rates are printed, never asserted. */
#include <gtest/gtest.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/io/CDatasetFolderSource.h>
#include <immslam/io/CLiveCameraSource.h>
#include <immslam/io/CRawlogRecorder.h>
#include <immslam/io/CRawlogSource.h>
#include <immslam/io/dataset2rawlog.h>

#include <mrpt/config.h>  // MRPT_HAS_FFMPEG
#include <mrpt/core/Clock.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/serialization/CArchive.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <thread>
#include <unistd.h>

#include "temp_dir.h"

namespace fs = std::filesystem;
using namespace immslam;
using namespace immslam::io;

namespace
{
const std::string kShared = IMMSLAM_SHARED_DATA_DIR;

/** The io tests' temporary folder, named after this test program. */
struct TempDir : test::TempDir
{
  TempDir() : test::TempDir("live_test") {}
};

void writeText(const std::string& path, const std::string& text)
{
  std::ofstream f(path);
  f << text;
  ASSERT_TRUE(f.good()) << path;
}

/** A 320x240 BGR test picture that changes with i: smooth gradients (kind to lossy codecs) plus a
 * moving disc and a per-frame number pattern so that frames cannot be confused. */
cv::Mat makeFrame(int i, int w = 320, int h = 240)
{
  cv::Mat m(h, w, CV_8UC3);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c)
      m.at<cv::Vec3b>(r, c) = cv::Vec3b(uchar((c * 255) / w), uchar((r * 255) / h), uchar((i * 12) % 256));
  cv::circle(m, {30 + 12 * i, h / 2}, 18, {255, 255, 255}, -1, cv::LINE_AA);
  cv::putText(m, std::to_string(i), {10, 30}, cv::FONT_HERSHEY_SIMPLEX, 0.8, {0, 0, 0}, 2);
  return m;
}

double meanAbsDiff(const cv::Mat& a, const cv::Mat& b)
{
  if (a.size() != b.size() || a.type() != b.type()) return 1e9;
  cv::Mat d;
  cv::absdiff(a, b, d);
  const cv::Scalar s = cv::mean(d);
  double sum = 0;
  for (int k = 0; k < a.channels(); ++k) sum += s[k];
  return sum / a.channels();
}

/** Every next() result of a source, with the wall time spent in next(). */
struct TStream
{
  std::vector<TFrame> frames;
  std::vector<std::string> skipped;
  std::string endWhy;
  double seconds = 0;
  double fps() const { return seconds > 0 ? double(frames.size()) / seconds : 0; }
};

TStream readAll(CImageSource& src, std::size_t limit = 100000,
                const std::function<void(std::size_t)>& afterFrame = {})
{
  TStream s;
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < limit; ++k)
  {
    TFrame f;
    std::string why;
    const ENextStatus st = src.next(f, why);
    if (st == ENextStatus::End)
    {
      s.endWhy = why;
      break;
    }
    if (st == ENextStatus::Skipped)
      s.skipped.push_back(why);
    else
    {
      s.frames.push_back(std::move(f));
      if (afterFrame) afterFrame(s.frames.size());
    }
  }
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

/** Writes frames first..first+n-1 as PNG files named by `pattern` (one %05d). */
void writeImageDir(const std::string& dir, int first, int n, bool grey = false)
{
  fs::create_directories(dir);
  for (int i = first; i < first + n; ++i)
  {
    char name[64];
    std::snprintf(name, sizeof(name), "img_%05d.png", i);
    cv::Mat img = makeFrame(i);
    if (grey) cv::cvtColor(img, img, cv::COLOR_BGR2GRAY);
    ASSERT_TRUE(cv::imwrite((fs::path(dir) / name).string(), img));
  }
}

std::string imageDirIni(const std::string& dir, int start, int end, const std::string& extra = "")
{
  return "[CAMERA]\ngrabber_type = image_dir\nimage_dir_url = " + dir + "\nleft_format = img_%05d.png\n" +
         "start_index = " + std::to_string(start) + "\nend_index = " + std::to_string(end) + "\n" + extra;
}

/** The error message of constructing a live source, or "" if it did not throw. */
std::string openError(const std::string& ini, const std::string& section = "CAMERA", TLiveOptions o = {})
{
  try
  {
    CLiveCameraSource src(ini, section, o);
  }
  catch (const std::runtime_error& e)
  {
    return e.what();
  }
  return "";
}

void report(const std::string& what, const TStream& s, const std::string& size)
{
  std::cout << "[ rate     ] " << what << ": " << s.frames.size() << " frames " << size << " in "
            << s.seconds * 1e3 << " ms = " << s.fps() << " frames/s\n";
}

#if MRPT_HAS_FFMPEG
#define REQUIRE_MRPT_FFMPEG()
#else
#define REQUIRE_MRPT_FFMPEG() GTEST_SKIP() << "this MRPT was built without FFmpeg (MRPT_HAS_FFMPEG = 0)"
#endif

/** Writes a video with cv::VideoWriter; false if this OpenCV/FFmpeg cannot encode it. */
bool writeVideo(const std::string& path, int fourcc, int n)
{
  cv::VideoWriter w;
  try
  {
    if (!w.open(path, cv::CAP_FFMPEG, fourcc, 30.0, cv::Size(320, 240), true)) return false;
  }
  catch (const cv::Exception&)
  {
    return false;
  }
  for (int i = 0; i < n; ++i) w.write(makeFrame(i));
  w.release();
  return fs::exists(path) && fs::file_size(path) > 0;
}
}  // namespace

// ------------------------------------------------------------------------------------------------
TEST(LiveImageDir, AllFramesInOrderWithFrameIndexTime)
{
  TempDir tmp;
  const std::string dir = tmp / "seq";
  writeImageDir(dir, 3, 20);
  writeText(tmp / "grab.ini", imageDirIni(dir, 3, 22));

  TLiveOptions o;
  o.camera = camera::parseCalibLine("pinhole 320 240 200 200 160 120", "test");
  CLiveCameraSource src(tmp / "grab.ini", "CAMERA", o);
  EXPECT_EQ(src.grabberType(), "image_dir");
  EXPECT_EQ(src.timestampMode(), ETimestampMode::FrameIndex);
  EXPECT_EQ(src.sizeHint(), 20u);
  EXPECT_EQ(src.calibration(), o.camera);
  EXPECT_NE(src.describe().find("image_dir"), std::string::npos) << src.describe();

  const TStream s = readAll(src);
  report("image_dir PNG colour", s, "320x240");
  ASSERT_EQ(s.frames.size(), 20u) << s.endWhy;
  EXPECT_TRUE(s.skipped.empty());
  for (int i = 0; i < 20; ++i)
  {
    const TFrame& f = s.frames[i];
    EXPECT_EQ(f.index, std::size_t(i));
    EXPECT_NEAR(f.timestamp, i / 30.0, 1e-12);
    const cv::Mat expected = makeFrame(i + 3);
    ASSERT_EQ(f.colour.type(), CV_8UC3);
    ASSERT_EQ(f.grey.type(), CV_8UC1);
    EXPECT_EQ(meanAbsDiff(f.colour, expected), 0.0) << "frame " << i;
    cv::Mat g;
    cv::cvtColor(expected, g, cv::COLOR_BGR2GRAY);
    EXPECT_EQ(meanAbsDiff(f.grey, g), 0.0) << "frame " << i;
    EXPECT_EQ(f.camera, o.camera);
    EXPECT_NE(f.origin.find("img_" + cv::format("%05d", i + 3) + ".png"), std::string::npos) << f.origin;
  }
  EXPECT_NE(s.endWhy.find("end of image sequence"), std::string::npos) << s.endWhy;
  EXPECT_NE(s.endWhy.find("end_index 22"), std::string::npos) << s.endWhy;
  EXPECT_TRUE(src.warnings().empty());
  // End is sticky.
  TFrame f;
  std::string why;
  EXPECT_EQ(src.next(f, why), ENextStatus::End);
  EXPECT_EQ(why, s.endWhy);
  EXPECT_EQ(src.framesDelivered(), 20u);
}

TEST(LiveImageDir, EndsAtFirstMissingImageAndRateOption)
{
  TempDir tmp;
  writeImageDir(tmp / "seq", 0, 5, /*grey*/ true);
  // No end_index: MRPT's default (100) is past the last file.
  writeText(tmp / "grab.ini",
            "[CAMERA]\ngrabber_type = image_dir\nimage_dir_url = seq\nleft_format = img_%05d.png\n");
  TLiveOptions o;
  o.frameRateHz = 15;
  // image_dir_url is relative: not found from the current directory, found beside the ini.
  CLiveCameraSource src(tmp / "grab.ini", "CAMERA", o);
  EXPECT_EQ(src.calibration(), nullptr);
  const TStream s = readAll(src);
  ASSERT_EQ(s.frames.size(), 5u) << s.endWhy;
  for (int i = 0; i < 5; ++i)
  {
    EXPECT_NEAR(s.frames[i].timestamp, i / 15.0, 1e-12);
    EXPECT_TRUE(s.frames[i].colour.empty()) << "grey input keeps no colour image";
    cv::Mat g;
    cv::cvtColor(makeFrame(i), g, cv::COLOR_BGR2GRAY);
    EXPECT_EQ(meanAbsDiff(s.frames[i].grey, g), 0.0);
    EXPECT_EQ(s.frames[i].camera, nullptr);
  }
  EXPECT_NE(s.endWhy.find("no image"), std::string::npos) << s.endWhy;
  EXPECT_NE(s.endWhy.find("img_00005.png"), std::string::npos) << s.endWhy;
}

TEST(LiveImageDir, APacedReplayComesNoFasterThanItsFrameRate)
{
  // TLiveOptions::paced: frame n is delivered no earlier than n / f after the first (a camera's
  // pace); the frames themselves are those of an unpaced replay.
  TempDir tmp;
  writeImageDir(tmp / "seq", 0, 7);
  writeText(tmp / "grab.ini", imageDirIni(tmp / "seq", 0, 6, ""));
  TLiveOptions o;
  o.frameRateHz = 20;
  o.paced = true;
  CLiveCameraSource src(tmp / "grab.ini", "CAMERA", o);
  std::vector<std::chrono::steady_clock::time_point> at;  // when each frame was delivered
  const TStream paced = readAll(src, 100000, [&](std::size_t) { at.push_back(std::chrono::steady_clock::now()); });
  ASSERT_EQ(paced.frames.size(), 7u) << paced.endWhy;
  for (std::size_t i = 1; i < at.size(); ++i)
  {
    EXPECT_NEAR(paced.frames[i].timestamp, static_cast<double>(i) / 20, 1e-12);
    EXPECT_GE(std::chrono::duration<double>(at[i] - at[0]).count(), paced.frames[i].timestamp - 1e-3) << i;
  }
  o.paced = false;
  CLiveCameraSource plain(tmp / "grab.ini", "CAMERA", o);
  const TStream s = readAll(plain);
  ASSERT_EQ(s.frames.size(), 7u);
  for (std::size_t i = 0; i < s.frames.size(); ++i)
  {
    EXPECT_EQ(s.frames[i].timestamp, paced.frames[i].timestamp);
    EXPECT_EQ(meanAbsDiff(s.frames[i].grey, paced.frames[i].grey), 0.0);
  }
}

TEST(LiveImageDir, SourceTimestampsGreyCaptureStereoLeftAndSizeWarning)
{
  TempDir tmp;
  writeImageDir(tmp / "seq", 0, 4);
  // Right images: the same files (the test only checks that the left one is delivered).
  writeText(tmp / "grab.ini",
            imageDirIni(tmp / "seq", 0, 3, "right_format = img_%05d.png\ncapture_grayscale = true\n"));
  TLiveOptions o;
  o.timestampMode = ETimestampMode::Source;
  o.camera = camera::parseCalibLine("pinhole 640 480 400 400 320 240", "test");
  const double before = mrpt::Clock::toDouble(mrpt::Clock::now());
  CLiveCameraSource src(tmp / "grab.ini", "CAMERA", o);
  const TStream s = readAll(src);
  const double after = mrpt::Clock::toDouble(mrpt::Clock::now());
  ASSERT_EQ(s.frames.size(), 4u) << s.endWhy;
  for (std::size_t i = 0; i < s.frames.size(); ++i)
  {
    // Wall-clock time of the grab.
    EXPECT_GE(s.frames[i].timestamp, before - 1e-3);
    EXPECT_LE(s.frames[i].timestamp, after + 1e-3);
    if (i > 0)
    {
      EXPECT_GE(s.frames[i].timestamp, s.frames[i - 1].timestamp);
    }
    EXPECT_TRUE(s.frames[i].colour.empty()) << "capture_grayscale";
    cv::Mat g;
    cv::cvtColor(makeFrame(int(i)), g, cv::COLOR_BGR2GRAY);
    // Exact: OpenCV's BGR -> grey (MRPT's CImage::grayscale() would swap red and blue here).
    EXPECT_EQ(meanAbsDiff(s.frames[i].grey, g), 0.0);
  }
  // A calibration of another size: frames still delivered, one warning.
  ASSERT_EQ(src.warnings().size(), 1u);
  EXPECT_NE(src.warnings()[0].find("320x240"), std::string::npos) << src.warnings()[0];
}

TEST(LiveImageDir, GrabDecimationDropsFrames)
{
  TempDir tmp;
  writeImageDir(tmp / "seq", 0, 10);
  writeText(tmp / "grab.ini", imageDirIni(tmp / "seq", 0, 9, "grab_decimation = 2\n"));
  TLiveOptions o;
  o.frameRateHz = 15;
  CLiveCameraSource src(tmp / "grab.ini", "CAMERA", o);
  const TStream s = readAll(src);
  // CCameraSensor returns a null observation for each dropped grab: images 1, 3, 5, 7, 9 remain.
  ASSERT_EQ(s.frames.size(), 5u) << s.endWhy;
  EXPECT_TRUE(s.skipped.empty());
  for (int k = 0; k < 5; ++k)
  {
    EXPECT_EQ(meanAbsDiff(s.frames[k].colour, makeFrame(2 * k + 1)), 0.0) << k;
    EXPECT_NE(s.frames[k].origin.find(cv::format("img_%05d.png", 2 * k + 1)), std::string::npos)
        << s.frames[k].origin;
    EXPECT_NEAR(s.frames[k].timestamp, k / 15.0, 1e-12);
  }
}

TEST(LiveImageDir, SharedDataSameFramesAsDatasetFolder)
{
  const fs::path folder = fs::path(kShared) / "visp_rbt";
  if (!fs::exists(folder / "rgb" / "color_image_0001.png"))
    GTEST_SKIP() << "shared data set visp_rbt not found under " << kShared;
  TempDir tmp;
  writeText(tmp / "grab.ini", "[CAMERA]\ngrabber_type = image_dir\nimage_dir_url = " + (folder / "rgb").string() +
                                  "\nleft_format = color_image_%04d.png\nstart_index = 0\nend_index = 98\n");
  CDatasetFolderSource ds(folder.string());
  const TStream b = readAll(ds);  // first: the files are then in the page cache for both
  CLiveCameraSource live(tmp / "grab.ini");
  const TStream a = readAll(live);
  report("image_dir PNG colour (visp_rbt)", a, "640x480");
  report("dataset folder (visp_rbt), for comparison", b, "640x480");
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (std::size_t i = 0; i < a.frames.size(); ++i)
  {
    EXPECT_EQ(meanAbsDiff(a.frames[i].colour, b.frames[i].colour), 0.0) << i;
    EXPECT_EQ(meanAbsDiff(a.frames[i].grey, b.frames[i].grey), 0.0) << i;
  }
}

// ------------------------------------------------------------------------------------------------
TEST(LiveFfmpeg, LosslessVideoAllFramesExact)
{
  REQUIRE_MRPT_FFMPEG();
  TempDir tmp;
  const std::string video = tmp / "video.mkv";
  const int n = 30;
  if (!writeVideo(video, cv::VideoWriter::fourcc('F', 'F', 'V', '1'), n))
    GTEST_SKIP() << "this OpenCV cannot write FFV1 .mkv through FFmpeg";
  writeText(tmp / "grab.ini", "[VIDEO]\ngrabber_type = ffmpeg\nffmpeg_url = " + video + "\n");
  CLiveCameraSource src(tmp / "grab.ini", "VIDEO");
  EXPECT_EQ(src.timestampMode(), ETimestampMode::FrameIndex);
  const TStream s = readAll(src);
  report("ffmpeg FFV1 .mkv", s, "320x240");
  ASSERT_EQ(s.frames.size(), std::size_t(n)) << s.endWhy;
  for (int i = 0; i < n; ++i)
  {
    EXPECT_NEAR(s.frames[i].timestamp, i / 30.0, 1e-12);
    ASSERT_EQ(s.frames[i].colour.type(), CV_8UC3);
    EXPECT_LT(meanAbsDiff(s.frames[i].colour, makeFrame(i)), 3.0) << "frame " << i;
    EXPECT_EQ(meanAbsDiff(s.frames[i].colour, makeFrame(i)), 0.0) << "FFV1 is lossless, frame " << i;
  }
  EXPECT_NE(s.endWhy.find("end of video"), std::string::npos) << s.endWhy;
}

TEST(LiveFfmpeg, MjpegVideoCloseAndGreyCapture)
{
  REQUIRE_MRPT_FFMPEG();
  TempDir tmp;
  const std::string video = tmp / "video.avi";
  const int n = 25;
  if (!writeVideo(video, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), n))
    GTEST_SKIP() << "this OpenCV cannot write MJPG .avi through FFmpeg";
  writeText(tmp / "grab.ini", "[VIDEO]\ngrabber_type = ffmpeg\nffmpeg_url = " + video +
                                  "\n[VIDEO_GREY]\ngrabber_type = ffmpeg\nffmpeg_url = " + video +
                                  "\ncapture_grayscale = true\n");
  {
    CLiveCameraSource src(tmp / "grab.ini", "VIDEO");
    const TStream s = readAll(src);
    report("ffmpeg MJPG .avi", s, "320x240");
    ASSERT_EQ(s.frames.size(), std::size_t(n)) << s.endWhy;
    for (int i = 0; i < n; ++i) EXPECT_LT(meanAbsDiff(s.frames[i].colour, makeFrame(i)), 3.0) << i;
    EXPECT_NE(s.endWhy.find("end of video"), std::string::npos) << s.endWhy;
  }
  {
    CLiveCameraSource src(tmp / "grab.ini", "VIDEO_GREY");
    const TStream s = readAll(src);
    ASSERT_EQ(s.frames.size(), std::size_t(n)) << s.endWhy;
    for (int i = 0; i < n; ++i)
    {
      EXPECT_TRUE(s.frames[i].colour.empty());
      cv::Mat g;
      cv::cvtColor(makeFrame(i), g, cv::COLOR_BGR2GRAY);
      EXPECT_LT(meanAbsDiff(s.frames[i].grey, g), 3.0) << i;
    }
  }
}

TEST(LiveFfmpeg, MissingOrBrokenVideoThrows)
{
  REQUIRE_MRPT_FFMPEG();
  TempDir tmp;
  writeText(tmp / "not_a_video.mkv", "this is not a video file\n");
  writeText(tmp / "grab.ini", "[A]\ngrabber_type = ffmpeg\nffmpeg_url = " + (tmp / "missing.mkv") +
                                  "\n[B]\ngrabber_type = ffmpeg\nffmpeg_url = " + (tmp / "not_a_video.mkv") +
                                  "\n[C]\ngrabber_type = ffmpeg\n");
  std::string e = openError(tmp / "grab.ini", "A");
  EXPECT_NE(e.find("ffmpeg_url"), std::string::npos) << e;
  EXPECT_NE(e.find("missing.mkv"), std::string::npos) << e;
  e = openError(tmp / "grab.ini", "B");
  EXPECT_NE(e.find("[B]"), std::string::npos) << e;
  EXPECT_NE(e.find("not_a_video.mkv"), std::string::npos) << e;
  e = openError(tmp / "grab.ini", "C");
  EXPECT_NE(e.find("ffmpeg_url is missing"), std::string::npos) << e;
}

// ------------------------------------------------------------------------------------------------
namespace
{
/** A small dataset folder: n colour frames, calib.txt, rgb.txt with non-uniform times. */
std::string makeDataset(const TempDir& tmp, int n)
{
  const std::string dir = tmp / "dataset";
  fs::create_directories(fs::path(dir) / "rgb");
  std::ofstream rgb(fs::path(dir) / "rgb.txt");
  rgb << "# timestamp path\n";
  for (int i = 0; i < n; ++i)
  {
    const std::string name = cv::format("rgb/%06d.png", i);
    cv::imwrite((fs::path(dir) / name).string(), makeFrame(i));
    rgb << cv::format("%.6f ", 1000.0 + 0.04 * i + (i % 3) * 0.001) << name << "\n";
  }
  writeText((fs::path(dir) / "calib.txt").string(), "opencv 320 240 210 211 161 119 -0.1 0.01 0.001 -0.002 0\n");
  return dir;
}
}  // namespace

TEST(LiveRawlog, SameFramesAsRawlogSourceExternalAndEmbedded)
{
  TempDir tmp;
  const std::string ds = makeDataset(tmp, 12);
  struct TCase
  {
    const char* name;
    bool embed;
    ERawlogLayout layout;
  };
  for (const TCase& c : {TCase{"external", false, ERawlogLayout::Observations},
                         TCase{"embedded", true, ERawlogLayout::Observations},
                         TCase{"embedded-sf", true, ERawlogLayout::SensoryFrames}})
  {
    SCOPED_TRACE(c.name);
    const bool embed = c.embed;
    const std::string rawlog = tmp / (std::string(c.name) + ".rawlog");
    TDataset2RawlogOptions opt;
    opt.embedImages = embed;
    opt.layout = c.layout;
    const TDataset2RawlogResult r = convertDatasetToRawlog(ds, rawlog, opt);
    ASSERT_EQ(r.nImages, 12u);
    ASSERT_TRUE(r.calibrationStored);
    writeText(tmp / "grab.ini", "[CAMERA]\ngrabber_type = rawlog\nrawlog_file = " + rawlog + "\n");

    CLiveCameraSource live(tmp / "grab.ini");
    EXPECT_EQ(live.timestampMode(), ETimestampMode::Source);
    CRawlogSource ref(rawlog);
    ASSERT_TRUE(live.calibration());
    ASSERT_TRUE(ref.calibration());
    EXPECT_EQ(live.calibration()->toCalibLine(), ref.calibration()->toCalibLine());
    EXPECT_EQ(live.calibration()->modelName(), "opencv");

    const TStream a = readAll(live);
    const TStream b = readAll(ref);
    report(std::string("rawlog grabber, ") + c.name + " images", a, "320x240");
    ASSERT_EQ(a.frames.size(), 12u) << a.endWhy;
    ASSERT_EQ(b.frames.size(), 12u) << b.endWhy;
    for (std::size_t i = 0; i < a.frames.size(); ++i)
    {
      EXPECT_EQ(a.frames[i].timestamp, b.frames[i].timestamp) << i;
      EXPECT_EQ(meanAbsDiff(a.frames[i].colour, b.frames[i].colour), 0.0) << i;
      EXPECT_EQ(meanAbsDiff(a.frames[i].grey, b.frames[i].grey), 0.0) << i;
      ASSERT_TRUE(a.frames[i].camera);
      EXPECT_EQ(a.frames[i].camera->toCalibLine(), b.frames[i].camera->toCalibLine());
    }
    EXPECT_NE(a.endWhy.find("end of rawlog"), std::string::npos) << a.endWhy;
  }
}

TEST(LiveRawlog, OtherObservationsIgnoredAndEmptyRawlogThrows)
{
  TempDir tmp;
  const std::string rawlog = tmp / "mixed.rawlog";
  {
    mrpt::io::CFileGZOutputStream f(rawlog);
    auto arch = mrpt::serialization::archiveFrom(f);
    for (int i = 0; i < 3; ++i)
    {
      mrpt::obs::CObservationComment c;
      c.text = "hello";
      arch << c;
      mrpt::obs::CObservationImage im;
      im.timestamp = mrpt::Clock::fromDouble(5.0 + i);
      cv::Mat g;
      cv::cvtColor(makeFrame(i), g, cv::COLOR_BGR2GRAY);
      im.image = mrpt::img::CImage(g, mrpt::img::DEEP_COPY);
      arch << im;
    }
  }
  writeText(tmp / "grab.ini", "[CAMERA]\ngrabber_type = rawlog\nrawlog_file = " + rawlog +
                                  "\n[EMPTY]\ngrabber_type = rawlog\nrawlog_file = " + (tmp / "empty.rawlog") + "\n");
  CLiveCameraSource live(tmp / "grab.ini");
  EXPECT_EQ(live.calibration(), nullptr);
  const TStream s = readAll(live);
  ASSERT_EQ(s.frames.size(), 3u) << s.endWhy;
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(s.frames[i].timestamp, 5.0 + i, 1e-6);

  { mrpt::io::CFileGZOutputStream f(tmp / "empty.rawlog"); }
  const std::string e = openError(tmp / "grab.ini", "EMPTY");
  EXPECT_NE(e.find("no first frame"), std::string::npos) << e;
  EXPECT_NE(e.find("end of rawlog"), std::string::npos) << e;
}

// ------------------------------------------------------------------------------------------------
TEST(LiveStop, RequestStopEndsTheStream)
{
  TempDir tmp;
  writeImageDir(tmp / "seq", 0, 10);
  writeText(tmp / "grab.ini", imageDirIni(tmp / "seq", 0, 9));
  {
    CLiveCameraSource src(tmp / "grab.ini");
    const TStream s = readAll(src, 100, [&](std::size_t n) {
      if (n == 3) src.requestStop();
    });
    EXPECT_EQ(s.frames.size(), 3u);
    EXPECT_EQ(s.endWhy, "stopped by user");
    EXPECT_TRUE(src.stopRequested());
    TFrame f;
    std::string why;
    EXPECT_EQ(src.next(f, why), ENextStatus::End);
    EXPECT_EQ(why, "stopped by user");
  }
  {
    // From another thread, while next() is being called.
    CLiveCameraSource src(tmp / "grab.ini");
    std::atomic<bool> go{false};
    std::thread t([&] {
      while (!go.load()) std::this_thread::yield();
      src.requestStop();
    });
    go = true;
    t.join();
    const TStream s = readAll(src);
    EXPECT_EQ(s.frames.size(), 0u);
    EXPECT_EQ(s.endWhy, "stopped by user");
  }
}

// ------------------------------------------------------------------------------------------------
TEST(LiveErrors, ClearMessagesNamingFileSectionAndKey)
{
  TempDir tmp;
  writeImageDir(tmp / "seq", 0, 2);
  const std::string ini = tmp / "grab.ini";
  writeText(ini, "[CAMERA]\ngrabber_type = image_dir\nimage_dir_url = " + (tmp / "seq") +
                     "\nleft_format = img_%05d.png\n"
                     "[NOTYPE]\ncv_camera_index = 0\n"
                     "[BADTYPE]\ngrabber_type = webcam\n"
                     "[UNKNOWNKEY]\ngrabber_type = image_dir\nimage_dir_url = " + (tmp / "seq") +
                     "\nleft_format = img_%05d.png\nframe_rate = 30\n"
                     "[TRAP]\ngrabber_type = image_dir\nimage_dir_url = " + (tmp / "seq") +
                     "\nleft_filename_format = img_%05d.png\n"
                     "[NOFORMAT]\ngrabber_type = image_dir\nimage_dir_url = " + (tmp / "seq") + "\n"
                     "[BADFORMAT]\ngrabber_type = image_dir\nimage_dir_url = " + (tmp / "seq") +
                     "\nleft_format = img_%s.png\n"
                     "[TWOCONV]\ngrabber_type = image_dir\nimage_dir_url = " + (tmp / "seq") +
                     "\nleft_format = img_%d_%d.png\n"
                     "[NODIR]\ngrabber_type = image_dir\nimage_dir_url = " + (tmp / "nowhere") +
                     "\nleft_format = img_%05d.png\n"
                     "[NOFIRST]\ngrabber_type = image_dir\nimage_dir_url = " + (tmp / "seq") +
                     "\nleft_format = img_%05d.png\nstart_index = 7\nend_index = 9\n"
                     "[NORAWLOG]\ngrabber_type = rawlog\nrawlog_file = " + (tmp / "none.rawlog") + "\n"
                     "[NOCAM]\ngrabber_type = opencv\ncv_camera_index = 63\n");

  auto expectError = [&](const std::string& section, const std::vector<std::string>& parts) {
    const std::string e = openError(ini, section);
    ASSERT_FALSE(e.empty()) << "[" << section << "] did not throw";
    for (const auto& p : parts) EXPECT_NE(e.find(p), std::string::npos) << "[" << section << "]: " << e;
  };
  {
    const std::string e = openError(tmp / "missing.ini");
    EXPECT_NE(e.find("missing.ini"), std::string::npos) << e;
  }
  expectError("NOSUCH", {ini, "[NOSUCH] not found", "CAMERA", "BADTYPE"});
  expectError("NOTYPE", {ini, "[NOTYPE]", "grabber_type is missing"});
  expectError("BADTYPE", {"[BADTYPE]", "unknown grabber_type 'webcam'", "image_dir"});
  expectError("UNKNOWNKEY", {"[UNKNOWNKEY]", "unknown key 'frame_rate'"});
  expectError("TRAP", {"[TRAP]", "left_filename_format", "left_format"});
  expectError("NOFORMAT", {"[NOFORMAT]", "left_format is missing"});
  expectError("BADFORMAT", {"[BADFORMAT]", "left_format", "img_%s.png"});
  expectError("TWOCONV", {"[TWOCONV]", "left_format", "more than one"});
  expectError("NODIR", {"[NODIR]", "image_dir_url", "nowhere"});
  expectError("NOFIRST", {"[NOFIRST]", "first image not found", "img_00007.png"});
  expectError("NORAWLOG", {"[NORAWLOG]", "rawlog_file", "none.rawlog"});
  const auto t0 = std::chrono::steady_clock::now();
  expectError("NOCAM", {"[NOCAM]", "cannot open the camera", "cv_camera_index = 63"});
  std::cout << "[ info     ] opencv grabber on a missing device failed in "
            << std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() << " s\n";
  // A section name is matched case-insensitively, as MRPT does.
  EXPECT_EQ(openError(ini, "camera"), "");
  // strictKeys = false accepts the unknown key.
  TLiveOptions lax;
  lax.strictKeys = false;
  EXPECT_EQ(openError(ini, "UNKNOWNKEY", lax), "");
}

TEST(LiveErrors, DocumentedExampleSectionsAreAccepted)
{
  // The three example files of CLiveCameraSource.h, verbatim but for the paths.
  TempDir tmp;
  writeImageDir(tmp / "sequences/corridor", 0, 3);
  fs::create_directories(tmp / "videos");
  writeText(tmp / "usb_camera.ini",
            "# usb_camera.ini: a USB camera (V4L2 /dev/video0) through OpenCV. Calibrate with --calib.\n"
            "[CAMERA]\ngrabber_type     = opencv\ncv_camera_index  = 0\ncv_frame_width   = 640\n"
            "cv_frame_height  = 480\n# capture_grayscale = true\n");
  writeText(tmp / "video_file.ini",
            "[CAMERA]\ngrabber_type     = ffmpeg\nffmpeg_url       = videos/corridor.mkv\n");
  writeText(tmp / "image_folder.ini",
            "[CAMERA]\ngrabber_type     = image_dir\nimage_dir_url    = sequences/corridor\n"
            "left_format      = img_%05d.png\nstart_index      = 0\nend_index        = 499\n");
  {
    CLiveCameraSource src(tmp / "image_folder.ini");  // paths relative to the ini's folder
    const TStream s = readAll(src);
    EXPECT_EQ(s.frames.size(), 3u);
    EXPECT_NE(s.endWhy.find("img_00003.png"), std::string::npos) << s.endWhy;
  }
#if MRPT_HAS_FFMPEG
  if (writeVideo(tmp / "videos/corridor.mkv", cv::VideoWriter::fourcc('F', 'F', 'V', '1'), 4))
  {
    CLiveCameraSource src(tmp / "video_file.ini");
    EXPECT_EQ(readAll(src).frames.size(), 4u);
  }
#endif
  // No camera here (normally): the keys pass, opening the device fails.
  const std::string e = openError(tmp / "usb_camera.ini");
  EXPECT_TRUE(e.empty() || e.find("cannot open the camera") != std::string::npos) << e;
}

TEST(LiveErrors, SplitLiveSpec)
{
  EXPECT_EQ(splitLiveSpec("grab.ini"), std::make_pair(std::string("grab.ini"), std::string("CAMERA")));
  EXPECT_EQ(splitLiveSpec("dir/grab.ini:USB"), std::make_pair(std::string("dir/grab.ini"), std::string("USB")));
  EXPECT_EQ(splitLiveSpec("grab.ini:"), std::make_pair(std::string("grab.ini"), std::string("CAMERA")));
  EXPECT_EQ(splitLiveSpec("a:b/grab.ini"), std::make_pair(std::string("a:b/grab.ini"), std::string("CAMERA")));
}

// ------------------------------------------------------------------------------------------------
namespace
{
void expectSameFrames(const std::vector<TFrame>& a, const std::vector<TFrame>& b)
{
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    EXPECT_NEAR(a[i].timestamp, b[i].timestamp, 1e-6) << i;
    EXPECT_EQ(meanAbsDiff(a[i].grey, b[i].grey), 0.0) << i;
    EXPECT_EQ(a[i].colour.empty(), b[i].colour.empty()) << i;
    if (!a[i].colour.empty())
    {
      EXPECT_EQ(meanAbsDiff(a[i].colour, b[i].colour), 0.0) << i;
    }
    ASSERT_EQ(bool(a[i].camera), bool(b[i].camera)) << i;
    if (a[i].camera)
    {
      EXPECT_EQ(a[i].camera->toCalibLine(), b[i].camera->toCalibLine()) << i;
    }
  }
}
}  // namespace

TEST(RawlogRecorder, LiveSessionRoundTrip)
{
  TempDir tmp;
  writeImageDir(tmp / "seq", 0, 20);
  writeText(tmp / "grab.ini", imageDirIni(tmp / "seq", 0, 19));
  TLiveOptions o;
  o.camera = camera::parseCalibLine("opencv 320 240 200 201 160 120 -0.2 0.05 0.001 0.002 0", "test");

  struct TCase
  {
    const char* name;
    bool embed;
    ERecordMode mode;
  };
  for (const TCase& c : {TCase{"embedded frames", true, ERecordMode::Frames},
                         TCase{"external PNG frames", false, ERecordMode::Frames},
                         TCase{"raw observations", true, ERecordMode::RawObservations}})
  {
    SCOPED_TRACE(c.name);
    const std::string out = tmp / (std::string(c.embed ? "emb" : "ext") +
                                   (c.mode == ERecordMode::Frames ? "_frames" : "_raw") + ".rawlog");
    CLiveCameraSource src(tmp / "grab.ini", "CAMERA", o);
    TRecorderOptions ro;
    ro.embedImages = c.embed;
    auto rec = std::make_shared<CRawlogRecorder>(out, ro);
    src.setRecorder(rec, c.mode);
    const TStream live = readAll(src);
    rec->close();
    EXPECT_FALSE(rec->isOpen());
    ASSERT_EQ(live.frames.size(), 20u);
    EXPECT_EQ(c.mode == ERecordMode::Frames ? rec->framesRecorded() : rec->objectsRecorded(), 20u);
    if (!c.embed)
    {
      EXPECT_TRUE(fs::exists(tmp / "ext_frames_Images/CAMERA_000019.png"));
    }

    auto back = openImageSource(out);
    const TStream replay = readAll(*back);
    EXPECT_TRUE(replay.skipped.empty()) << replay.skipped.front();
    EXPECT_EQ(replay.endWhy, "");
    if (c.mode == ERecordMode::Frames)
      expectSameFrames(live.frames, replay.frames);
    else
    {
      // Raw observations carry no calibration (image_dir): compare without it.
      ASSERT_EQ(replay.frames.size(), live.frames.size());
      for (std::size_t i = 0; i < live.frames.size(); ++i)
      {
        EXPECT_NEAR(replay.frames[i].timestamp, live.frames[i].timestamp, 1e-6);
        EXPECT_EQ(meanAbsDiff(replay.frames[i].colour, live.frames[i].colour), 0.0);
        EXPECT_EQ(replay.frames[i].camera, nullptr);
      }
    }
  }
}

TEST(RawlogRecorder, StandaloneGreyFramesErrorsAndDestructorCloses)
{
  TempDir tmp;
  const std::string out = tmp / "grey.rawlog";
  std::vector<TFrame> frames;
  {
    CRawlogRecorder rec(out);
    for (int i = 0; i < 5; ++i)
    {
      TFrame f;
      f.index = std::size_t(i);
      f.timestamp = 1.7e9 + i * 0.033;  // wall-clock-like times keep their precision
      cv::cvtColor(makeFrame(i), f.grey, cv::COLOR_BGR2GRAY);
      rec.record(f);
      frames.push_back(f);
    }
    TFrame empty;
    EXPECT_THROW(rec.record(empty), std::runtime_error);
    EXPECT_EQ(rec.framesRecorded(), 5u);
  }  // destructor closes
  CRawlogSource back(out);
  const TStream s = readAll(back);
  expectSameFrames(frames, s.frames);
  EXPECT_EQ(back.calibration(), nullptr);

  // Colour dropped on request; a davison camera (not representable by TCamera) is not stored.
  {
    TRecorderOptions ro;
    ro.keepColour = false;
    CRawlogRecorder rec(tmp / "nocolour.rawlog", ro);
    TFrame f;
    f.colour = makeFrame(1);
    cv::cvtColor(f.colour, f.grey, cv::COLOR_BGR2GRAY);
    f.camera = camera::parseCalibLine("davison 320 240 195 195 162 125 9e-06", "test");
    rec.record(f);
    rec.close();
    rec.close();  // idempotent
    EXPECT_THROW(rec.record(f), std::runtime_error);
    CRawlogSource b(tmp / "nocolour.rawlog");
    const TStream t = readAll(b);
    ASSERT_EQ(t.frames.size(), 1u);
    EXPECT_TRUE(t.frames[0].colour.empty());
    EXPECT_EQ(t.frames[0].camera, nullptr);
  }
  try
  {
    CRawlogRecorder rec(tmp / "no/such/dir/x.rawlog");
    ADD_FAILURE() << "no exception";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find("no/such/dir/x.rawlog"), std::string::npos) << e.what();
  }
}
