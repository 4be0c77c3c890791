/* Tests of libs/io: dataset folders, rawlogs (both layouts, embedded/external images, damage),
 * dataset2rawlog round trips on the shared data sets, CDatasetWriter, CCsvWriter. */
#include <gtest/gtest.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/camera/mrpt_camera.h>
#include <immslam/io/CCsvWriter.h>
#include <immslam/io/CDatasetFolderSource.h>
#include <immslam/io/CDatasetWriter.h>
#include <immslam/io/CRawlogSource.h>
#include <immslam/io/CVideoFileSource.h>
#include <immslam/io/dataset2rawlog.h>

#include <mrpt/core/Clock.h>
#include <mrpt/img/CImage.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CMemoryStream.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/obs/CObservationStereoImages.h>
#include <mrpt/serialization/CArchive.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>
#include <zlib.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
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
  TempDir() : test::TempDir("io_test") {}
};

std::string sharedDataset(const std::string& name)
{
  const fs::path p = fs::path(kShared) / name;
  return fs::exists(p / "rgb.txt") ? p.string() : std::string();
}

#define REQUIRE_DATASET(var, name)                                                          \
  const std::string var = sharedDataset(name);                                              \
  if (var.empty()) GTEST_SKIP() << "shared data set " << name << " not found under " << kShared

/** Every next() result of a source. */
struct TStream
{
  std::vector<TFrame> frames;
  std::vector<std::string> skipped;
  std::string endWhy;
};

TStream drain(CImageSource& src, bool keepPixels = true)
{
  TStream s;
  TFrame f;
  std::string why;
  for (int guard = 0; guard < 100000; ++guard)
  {
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
      // keepPixels = false: only the first and the last frame keep their pixels (saves memory).
      if (!keepPixels && s.frames.size() > 1)
      {
        s.frames.back().grey.release();
        s.frames.back().colour.release();
      }
      s.frames.push_back(f);
    }
  }
  return s;
}

bool sameImage(const cv::Mat& a, const cv::Mat& b)
{
  if (a.empty() || b.empty()) return a.empty() && b.empty();
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

double quatDistance(const Vec4& a, const Vec4& b) { return std::min((a - b).norm(), (a + b).norm()); }

void expectSameTrajectory(const core::TTrajectory& a, const core::TTrajectory& b)
{
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i)
  {
    EXPECT_NEAR(a[i].timestamp, b[i].timestamp, 1e-6) << i;
    EXPECT_LT((a[i].p_W_C - b[i].p_W_C).norm(), 1e-6) << i;
    EXPECT_LT(quatDistance(a[i].q_W_C, b[i].q_W_C), 1e-6) << i;
  }
}

/** A deterministic synthetic image (noise + gradient) of the given type. */
cv::Mat syntheticImage(int w, int h, int type, int seed)
{
  cv::Mat m(h, w, type);
  cv::RNG rng(seed);
  rng.fill(m, cv::RNG::UNIFORM, 0, CV_MAT_DEPTH(type) == CV_16U ? 65535 : 255);
  return m;
}

camera::CCameraModel::Ptr pinhole(int w, int h)
{
  return camera::makeCameraModel("pinhole", w, h, {100.0, 101.0, w / 2.0, h / 2.0});
}

/** Writes a synthetic dataset folder of n frames (colour or grey) with ground truth. */
void writeSyntheticDataset(const std::string& folder, int n, bool colour, int w = 64, int h = 48)
{
  CDatasetWriter wr(folder, *pinhole(w, h), "synthetic test sequence");
  for (int i = 0; i < n; ++i)
  {
    core::TStampedPose p;
    p.p_W_C = Vec3(0.1 * i, -0.2 * i, 0.05);
    p.q_W_C = Vec4(std::cos(0.05 * i), 0, std::sin(0.05 * i), 0);
    wr.addFrame(100.0 + i / 30.0, syntheticImage(w, h, colour ? CV_8UC3 : CV_8UC1, i), &p);
  }
  wr.close();
}

/** A dataset folder made of the first n entries (and the last one) of a shared data set, its
 * images referenced by absolute paths; calib.txt and groundtruth.txt copied. */
void writeSubsetDataset(const std::string& src, const std::string& dst, std::size_t n)
{
  CDatasetFolderSource s(src);
  std::ofstream rgb(dst + "/rgb.txt");
  rgb << "# subset of " << src << "\n";
  const auto& e = s.entries();
  for (std::size_t i = 0; i < e.size(); ++i)
    if (i < n || i + 1 == e.size())
    {
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%.6f ", e[i].timestamp);
      rgb << buf << fs::absolute(s.imagePath(e[i])).string() << "\n";
    }
  for (const char* f : {"calib.txt", "groundtruth.txt"})
    if (fs::exists(fs::path(src) / f)) fs::copy_file(fs::path(src) / f, fs::path(dst) / f);
}

std::string readAll(const std::string& path)
{
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}
}  // namespace

// ------------------------------------------------------------------------------------------------
// Dataset folders
// ------------------------------------------------------------------------------------------------

TEST(DatasetFolder, MissingRgbTxtThrowsNamingPath)
{
  TempDir d;
  try
  {
    CDatasetFolderSource s(d.str());
    FAIL() << "no exception";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(d / "rgb.txt"), std::string::npos) << e.what();
  }
  EXPECT_THROW(openImageSource(d / "does_not_exist"), std::runtime_error);
  try
  {
    openImageSource(d / "does_not_exist");
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(d / "does_not_exist"), std::string::npos) << e.what();
  }
}

TEST(DatasetFolder, MalformedLineSkippedWithLineNumber)
{
  TempDir d;
  writeSyntheticDataset(d.str(), 3, false);
  {
    std::ofstream rgb(d / "rgb.txt", std::ios::app);
    rgb << "not_a_number rgb/000000.png\n"  // line 6
        << "justonefield\n"                 // line 7
        << "\n# comment\n"
        << "200.5 rgb/000001.png\n";        // line 10
  }
  CDatasetFolderSource src(d.str());
  EXPECT_EQ(src.sizeHint(), 6u);
  ASSERT_TRUE(src.calibration());
  EXPECT_EQ(src.calibration()->modelName(), "pinhole");
  ASSERT_TRUE(src.groundTruth());
  EXPECT_EQ(src.groundTruth()->size(), 3u);
  const TStream s = drain(src);
  ASSERT_EQ(s.frames.size(), 4u);
  ASSERT_EQ(s.skipped.size(), 2u);
  EXPECT_NE(s.skipped[0].find("rgb.txt:6"), std::string::npos) << s.skipped[0];
  EXPECT_NE(s.skipped[1].find("rgb.txt:7"), std::string::npos) << s.skipped[1];
  EXPECT_EQ(s.endWhy, "");
  EXPECT_EQ(s.frames[3].index, 5u);
  EXPECT_DOUBLE_EQ(s.frames[3].timestamp, 200.5);
  EXPECT_EQ(s.frames[3].origin, "rgb/000001.png");
  EXPECT_TRUE(s.frames[0].colour.empty());
  EXPECT_EQ(s.frames[0].grey.type(), CV_8UC1);
}

TEST(DatasetFolder, MissingAndCorruptImagesSkipped)
{
  REQUIRE_DATASET(visp, "visp_rbt");
  TempDir d;
  fs::create_directories(d / "rgb");
  CDatasetFolderSource full(visp);
  std::ofstream rgb(d / "rgb.txt");
  for (std::size_t i = 0; i < 5; ++i)
  {
    const auto& e = full.entries()[i];
    fs::copy_file(full.imagePath(e), d / e.path);
    rgb << e.timestamp << " " << e.path << "\n";
  }
  rgb.close();
  const std::string missing = d / full.entries()[1].path;
  const std::string corrupt = d / full.entries()[3].path;
  fs::remove(missing);
  fs::resize_file(corrupt, 100);  // header only: undecodable
  CDatasetFolderSource src(d.str());
  EXPECT_EQ(src.calibration(), nullptr);
  EXPECT_FALSE(src.groundTruth());
  const TStream s = drain(src);
  ASSERT_EQ(s.frames.size(), 3u);
  ASSERT_EQ(s.skipped.size(), 2u);
  EXPECT_NE(s.skipped[0].find(missing), std::string::npos) << s.skipped[0];
  EXPECT_NE(s.skipped[0].find("missing"), std::string::npos) << s.skipped[0];
  EXPECT_NE(s.skipped[1].find(corrupt), std::string::npos) << s.skipped[1];
  EXPECT_EQ(s.frames[1].index, 2u);
  EXPECT_FALSE(s.frames[0].colour.empty());  // visp is RGB
  EXPECT_EQ(s.frames[0].colour.type(), CV_8UC3);
  EXPECT_EQ(s.frames[0].grey.type(), CV_8UC1);
}

TEST(DatasetFolder, SixteenBitAndAlphaImages)
{
  TempDir d;
  fs::create_directories(d / "rgb");
  const cv::Mat g16 = syntheticImage(40, 30, CV_16UC1, 1);
  const cv::Mat bgra = syntheticImage(40, 30, CV_8UC4, 2);
  ASSERT_TRUE(cv::imwrite(d / "rgb/a.png", g16));
  ASSERT_TRUE(cv::imwrite(d / "rgb/b.png", bgra));
  std::ofstream(d / "rgb.txt") << "1.0 rgb/a.png\n2.0 rgb/b.png\n";
  CDatasetFolderSource src(d.str());
  const TStream s = drain(src);
  ASSERT_EQ(s.frames.size(), 2u);
  cv::Mat expect8;
  g16.convertTo(expect8, CV_8U, 1.0 / 256.0);
  EXPECT_TRUE(sameImage(s.frames[0].grey, expect8));
  EXPECT_TRUE(s.frames[0].colour.empty());
  EXPECT_EQ(s.frames[1].colour.type(), CV_8UC3);
  EXPECT_EQ(s.frames[1].grey.type(), CV_8UC1);
}

TEST(DatasetWriter, RoundTrip)
{
  TempDir d;
  const int w = 50, h = 40;
  std::vector<cv::Mat> imgs;
  core::TTrajectory gt;
  {
    CDatasetWriter wr(d / "ds", *pinhole(w, h), "round trip");
    for (int i = 0; i < 4; ++i)
    {
      imgs.push_back(syntheticImage(w, h, i % 2 ? CV_8UC3 : CV_8UC1, 10 + i));
      core::TStampedPose p;
      p.timestamp = 5 + 0.1 * i;
      p.p_W_C = Vec3(i, 2 * i, -i);
      p.q_W_C = Vec4(1, 0.1 * i, 0, 0).normalized();
      gt.push_back(p);
      EXPECT_EQ(wr.addFrame(p.timestamp, imgs.back(), &p), "rgb/00000" + std::to_string(i) + ".png");
    }
    EXPECT_EQ(wr.frameCount(), 4u);
  }  // destructor closes
  EXPECT_NE(readAll(d / "ds/rgb.txt").find("5.100000 rgb/000001.png"), std::string::npos);
  EXPECT_EQ(readAll(d / "ds/rgb.txt").rfind("# round trip", 0), 0u);
  CDatasetFolderSource src(d / "ds");
  ASSERT_TRUE(src.calibration());
  EXPECT_EQ(src.calibration()->parameters(), pinhole(w, h)->parameters());
  ASSERT_TRUE(src.groundTruth());
  expectSameTrajectory(*src.groundTruth(), gt);
  const TStream s = drain(src);
  ASSERT_EQ(s.frames.size(), 4u);
  for (int i = 0; i < 4; ++i)
  {
    EXPECT_NEAR(s.frames[i].timestamp, gt[i].timestamp, 1e-9);
    EXPECT_TRUE(sameImage(i % 2 ? s.frames[i].colour : s.frames[i].grey, imgs[i])) << i;
  }
}

// ------------------------------------------------------------------------------------------------
// dataset2rawlog round trips on the shared data sets
// ------------------------------------------------------------------------------------------------

namespace
{
struct TRoundTripCase
{
  std::string dataset;
  ERawlogLayout layout;
  bool embed;
  std::size_t subset;  ///< 0: whole folder, else first N frames + the last one
};

void PrintTo(const TRoundTripCase& c, std::ostream* os)
{
  *os << c.dataset << (c.layout == ERawlogLayout::SensoryFrames ? " sf" : " obs")
      << (c.embed ? " embedded" : " external") << " subset=" << c.subset;
}

std::string caseName(const testing::TestParamInfo<TRoundTripCase>& info)
{
  return info.param.dataset + (info.param.layout == ERawlogLayout::SensoryFrames ? "_sf" : "_obs") +
         (info.param.embed ? "_embedded" : "_external") +
         (info.param.subset ? "_first" + std::to_string(info.param.subset) : "_all");
}

class RoundTrip : public testing::TestWithParam<TRoundTripCase>
{
};
}  // namespace

TEST_P(RoundTrip, SameFramesCalibrationAndGroundTruth)
{
  const TRoundTripCase& c = GetParam();
  REQUIRE_DATASET(shared, c.dataset);
  TempDir d;
  std::string folder = shared;
  if (c.subset)
  {
    folder = d / "subset";
    fs::create_directories(folder);
    writeSubsetDataset(shared, folder, c.subset);
  }
  // The rawlog in a sub-folder, so that external names need "../".
  fs::create_directories(d / "out");
  const std::string rawlog = d / "out/seq.rawlog";
  TDataset2RawlogOptions opts;
  opts.embedImages = c.embed;
  opts.layout = c.layout;
  const auto t0 = std::chrono::steady_clock::now();
  const TDataset2RawlogResult r = convertDatasetToRawlog(folder, rawlog, opts);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::cout << "[ timing   ] dataset2rawlog " << caseName({c, 0}) << ": " << r.nImages << " images, "
            << r.nGroundTruth << " GT poses, " << secs << " s, " << fs::file_size(rawlog) / 1024
            << " KiB\n";

  CDatasetFolderSource ref(folder);
  EXPECT_EQ(r.nImages, ref.sizeHint());
  EXPECT_EQ(r.nSkipped, 0u);
  EXPECT_EQ(r.nGroundTruth, ref.groundTruth() ? ref.groundTruth()->size() : 0u);

  CRawlogSource src(rawlog);
  EXPECT_EQ(src.damage(), "");
  EXPECT_EQ(src.sizeHint(), ref.sizeHint());
  EXPECT_EQ(src.hasSensoryFrames(), c.layout == ERawlogLayout::SensoryFrames);

  // Calibration: kept where TCamera can represent it (pinhole, opencv), else none + a warning.
  ASSERT_TRUE(ref.calibration());
  if (ref.calibration()->modelName() == "davison")
  {
    EXPECT_FALSE(r.calibrationStored);
    EXPECT_EQ(src.calibration(), nullptr);
    bool warned = false;
    for (const auto& w : r.warnings) warned |= w.find(ref.calibration()->toCalibLine()) != std::string::npos;
    EXPECT_TRUE(warned) << "the warning should print the calib.txt line";
  }
  else
  {
    EXPECT_TRUE(r.calibrationStored);
    ASSERT_TRUE(src.calibration());
    EXPECT_EQ(src.calibration()->modelName(), ref.calibration()->modelName());
    EXPECT_EQ(src.calibration()->width(), ref.calibration()->width());
    EXPECT_EQ(src.calibration()->height(), ref.calibration()->height());
    const auto a = src.calibration()->parameters(), b = ref.calibration()->parameters();
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-12 * (1 + std::abs(b[i])));
  }

  // Ground truth, complete before reading any frame.
  if (ref.groundTruth())
  {
    ASSERT_TRUE(src.groundTruth());
    expectSameTrajectory(*src.groundTruth(), *ref.groundTruth());
  }
  else
    EXPECT_FALSE(src.groundTruth());

  // Frames: same count and timestamps; same pixels for the first and the last frame.
  const TStream got = drain(src, false);
  EXPECT_TRUE(got.skipped.empty()) << (got.skipped.empty() ? "" : got.skipped[0]);
  EXPECT_EQ(got.endWhy, "");
  const auto& e = ref.entries();
  ASSERT_EQ(got.frames.size(), e.size());
  for (std::size_t i = 0; i < e.size(); ++i) EXPECT_NEAR(got.frames[i].timestamp, e[i].timestamp, 1e-6) << i;

  for (const std::size_t k : {std::size_t(0), e.size() - 1})
  {
    const TFrame& fr = k == 0 ? got.frames.front() : got.frames.back();
    TFrame ff;
    std::string why;
    ref.seek(k);
    ASSERT_EQ(ref.next(ff, why), ENextStatus::Frame) << why;
    EXPECT_TRUE(sameImage(fr.grey, ff.grey)) << "frame " << k;
    EXPECT_TRUE(sameImage(fr.colour, ff.colour)) << "frame " << k;
    EXPECT_FALSE(fr.grey.empty());
    if (src.calibration())
    {
      EXPECT_TRUE(fr.camera);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    SharedData, RoundTrip,
    testing::Values(
        TRoundTripCase{"monoslam_testseq", ERawlogLayout::Observations, false, 0},
        TRoundTripCase{"monoslam_testseq", ERawlogLayout::SensoryFrames, false, 0},
        TRoundTripCase{"monoslam_testseq", ERawlogLayout::Observations, true, 30},
        TRoundTripCase{"monoslam_testseq", ERawlogLayout::SensoryFrames, true, 30},
        TRoundTripCase{"visp_rbt", ERawlogLayout::Observations, false, 0},
        TRoundTripCase{"visp_rbt", ERawlogLayout::SensoryFrames, false, 0},
        TRoundTripCase{"visp_rbt", ERawlogLayout::Observations, true, 30},
        TRoundTripCase{"visp_rbt", ERawlogLayout::SensoryFrames, true, 30},
        TRoundTripCase{"euroc_v101_stationary", ERawlogLayout::Observations, false, 0},
        TRoundTripCase{"euroc_v101_stationary", ERawlogLayout::SensoryFrames, false, 0},
        TRoundTripCase{"euroc_v101_stationary", ERawlogLayout::Observations, true, 30},
        TRoundTripCase{"euroc_v101_stationary", ERawlogLayout::SensoryFrames, true, 30},
        TRoundTripCase{"monoslammot_synth19", ERawlogLayout::Observations, false, 0},
        TRoundTripCase{"monoslammot_synth19", ERawlogLayout::SensoryFrames, false, 0},
        TRoundTripCase{"monoslammot_synth19", ERawlogLayout::Observations, true, 30},
        TRoundTripCase{"monoslammot_synth19", ERawlogLayout::SensoryFrames, true, 30}),
    caseName);

// ------------------------------------------------------------------------------------------------
// Rawlogs written by hand
// ------------------------------------------------------------------------------------------------

TEST(Rawlog, GroundTruthNearGimbalLockExact)
{
  // Orientations within 0.3 deg of MRPT pitch = +-90 deg (and exactly at it), where MRPT's own
  // matrix -> yaw/pitch/roll conversion loses up to 5e-3: the round trip must stay exact.
  TempDir d;
  const std::vector<Vec4> qs = {Vec4(0, 0.70772401, 0, 0.70648901), Vec4(0, 0.70852486, 0, -0.70568586),
                                Vec4(0.70710678118654752, 0, 0.70710678118654752, 0),
                                Vec4(0.70710678118654752, 0, -0.70710678118654752, 0), Vec4(0.5, -0.5, 0.5, 0.5),
                                Vec4(0.1, 0.2, 0.3, 0.4)};
  core::TTrajectory gt;
  {
    CDatasetWriter wr(d / "ds", *pinhole(8, 8));
    for (std::size_t i = 0; i < qs.size(); ++i)
    {
      core::TStampedPose p;
      p.timestamp = static_cast<double>(i);
      p.p_W_C = Vec3(1.0 * i, 2, 3);
      p.q_W_C = qs[i].normalized();
      gt.push_back(p);
      wr.addFrame(p.timestamp, syntheticImage(8, 8, CV_8UC1, 0), &p);
    }
  }
  convertDatasetToRawlog(d / "ds", d / "g.rawlog");
  CRawlogSource src(d / "g.rawlog");
  ASSERT_TRUE(src.groundTruth());
  ASSERT_EQ(src.groundTruth()->size(), gt.size());
  for (std::size_t i = 0; i < gt.size(); ++i)
  {
    // groundtruth.txt keeps 8 decimals: compare with what the folder reader sees.
    const Vec4 want = (*CDatasetFolderSource(d / "ds").groundTruth())[i].q_W_C.normalized();
    EXPECT_LT(quatDistance((*src.groundTruth())[i].q_W_C, want), 1e-12) << i;
    EXPECT_GE((*src.groundTruth())[i].q_W_C[0], 0.0);
  }
}

TEST(Rawlog, MixedObservationsSkippedAndCounted)
{
  TempDir d;
  const std::string rawlog = d / "mixed.rawlog";
  std::vector<cv::Mat> imgs;
  {
    mrpt::io::CFileGZOutputStream f(rawlog);
    auto a = mrpt::serialization::archiveFrom(f);
    for (int i = 0; i < 5; ++i)
    {
      auto img = mrpt::obs::CObservationImage::Create();
      img->sensorLabel = "CAMERA";
      img->timestamp = mrpt::Clock::fromDouble(10.0 + i);
      imgs.push_back(syntheticImage(32, 24, CV_8UC1, i));
      img->image = mrpt::img::CImage(imgs.back(), mrpt::img::DEEP_COPY);
      a << *img;
      auto odo = mrpt::obs::CObservationOdometry::Create();
      odo->timestamp = img->timestamp;
      odo->sensorLabel = "ODOMETRY";
      a << *odo;
      auto gt = mrpt::obs::CObservationRobotPose::Create();
      gt->sensorLabel = i % 2 ? "GT" : "LOCALIZATION";  // only "GT" is ground truth
      gt->timestamp = img->timestamp;
      gt->pose.mean = mrpt::poses::CPose3D(i, 0, 0, 0.1 * i, 0, 0);
      a << *gt;
    }
    auto comment = mrpt::obs::CObservationComment::Create();
    comment->text = "hello";
    a << *comment;
  }
  CRawlogSource src(rawlog);
  EXPECT_EQ(src.sizeHint(), 5u + 5u + 3u + 1u);
  EXPECT_EQ(src.calibration(), nullptr);  // default (zero) cameraParams
  ASSERT_TRUE(src.groundTruth());
  ASSERT_EQ(src.groundTruth()->size(), 2u);
  const core::TTrajectory gtAll = *src.groundTruth();  // groundTruth() returns a copy: keep it alive
  const auto& g = gtAll[1];
  EXPECT_NEAR(g.timestamp, 13.0, 1e-6);
  EXPECT_NEAR(g.p_W_C.x(), 3.0, 1e-12);
  // yaw 0.3 about z: q = (cos 0.15, 0, 0, sin 0.15), scalar first.
  EXPECT_LT(quatDistance(g.q_W_C, Vec4(std::cos(0.15), 0, 0, std::sin(0.15))), 1e-12);
  const TStream s = drain(src);
  ASSERT_EQ(s.frames.size(), 5u);
  ASSERT_EQ(s.skipped.size(), 9u);
  EXPECT_NE(s.skipped[0].find("observation of class mrpt::obs::CObservationOdometry"), std::string::npos)
      << s.skipped[0];
  EXPECT_NE(s.skipped[1].find("CObservationRobotPose"), std::string::npos) << s.skipped[1];
  EXPECT_NE(s.skipped.back().find("CObservationComment"), std::string::npos) << s.skipped.back();
  for (int i = 0; i < 5; ++i)
  {
    EXPECT_TRUE(sameImage(s.frames[i].grey, imgs[i]));
    EXPECT_NEAR(s.frames[i].timestamp, 10.0 + i, 1e-6);
  }
  EXPECT_EQ(s.frames[1].index, 3u);  // after image, odometry, non-GT pose
  EXPECT_EQ(s.endWhy, "");
}

TEST(Rawlog, StereoAndRangeCameraImagesAreFramesOfTheirCamera)
{
  // What MRPT's grabbers log for a stereo rig (CObservationStereoImages: the left image and camera are
  // the frames) and an RGB-D camera (CObservation3DRangeScan: the intensity image and its camera);
  // a range scan without an intensity image carries nothing for a monocular system.
  TempDir d;
  const std::string rawlog = d / "stereo_rgbd.rawlog";
  const auto leftCam = camera::toTCamera(*pinhole(32, 24));
  const auto rightCam = camera::toTCamera(*camera::makeCameraModel("pinhole", 32, 24, {150.0, 150.0, 16.0, 12.0}));
  const auto irCam = camera::toTCamera(*camera::makeCameraModel("pinhole", 40, 30, {60.0, 60.0, 20.0, 15.0}));
  ASSERT_TRUE(leftCam && rightCam && irCam);
  std::vector<cv::Mat> left, ir;
  {
    mrpt::io::CFileGZOutputStream f(rawlog);
    auto a = mrpt::serialization::archiveFrom(f);
    for (int i = 0; i < 4; ++i)
    {
      auto st = mrpt::obs::CObservationStereoImages::Create();
      st->sensorLabel = "BUMBLEBEE";
      st->timestamp = mrpt::Clock::fromDouble(1.0 + i);
      left.push_back(syntheticImage(32, 24, CV_8UC1, i));
      st->imageLeft = mrpt::img::CImage(left.back(), mrpt::img::DEEP_COPY);
      st->imageRight = mrpt::img::CImage(syntheticImage(32, 24, CV_8UC1, 100 + i), mrpt::img::DEEP_COPY);
      st->hasImageRight = true;
      st->leftCamera = *leftCam;
      st->rightCamera = *rightCam;
      a << *st;
    }
  }
  CRawlogSource src(rawlog);
  ASSERT_TRUE(src.calibration());
  EXPECT_DOUBLE_EQ(src.calibration()->fx(), 100.0);  // the left camera's
  const TStream s = drain(src);
  ASSERT_EQ(s.frames.size(), 4u);
  EXPECT_TRUE(s.skipped.empty());
  for (int i = 0; i < 4; ++i)
  {
    EXPECT_TRUE(sameImage(s.frames[i].grey, left[i])) << i;
    EXPECT_NEAR(s.frames[i].timestamp, 1.0 + i, 1e-6);
    ASSERT_TRUE(s.frames[i].camera);
    EXPECT_DOUBLE_EQ(s.frames[i].camera->fx(), 100.0);
  }

  const std::string rgbd = d / "rgbd.rawlog";
  {
    mrpt::io::CFileGZOutputStream f(rgbd);
    auto a = mrpt::serialization::archiveFrom(f);
    for (int i = 0; i < 4; ++i)
    {
      auto r3 = mrpt::obs::CObservation3DRangeScan::Create();
      r3->sensorLabel = "KINECT";
      r3->timestamp = mrpt::Clock::fromDouble(5.0 + i);
      r3->hasIntensityImage = i != 2;  // entry 2: depth only
      if (r3->hasIntensityImage)
      {
        ir.push_back(syntheticImage(40, 30, CV_8UC1, 200 + i));
        r3->intensityImage = mrpt::img::CImage(ir.back(), mrpt::img::DEEP_COPY);
      }
      r3->cameraParamsIntensity = *irCam;
      a << *r3;
    }
  }
  CRawlogSource src3(rgbd);
  ASSERT_TRUE(src3.calibration());
  EXPECT_DOUBLE_EQ(src3.calibration()->fx(), 60.0);
  const TStream s3 = drain(src3);
  ASSERT_EQ(s3.frames.size(), 3u);
  ASSERT_EQ(s3.skipped.size(), 1u);
  EXPECT_NE(s3.skipped[0].find("CObservation3DRangeScan"), std::string::npos) << s3.skipped[0];
  for (std::size_t i = 0; i < ir.size(); ++i) EXPECT_TRUE(sameImage(s3.frames[i].grey, ir[i])) << i;
}

TEST(Rawlog, SeveralCamerasTheFirstOrTheOneChosenBySensorLabel)
{
  // Two cameras logged as CObservationImage with their own labels (a stereo rig recorded as two
  // monocular sensors): interleaving them would feed the filter two viewpoints. The frames are the
  // first camera's, or the one asked for; the others' images are skipped naming their sensor.
  TempDir d;
  const std::string rawlog = d / "two_cameras.rawlog";
  const auto camL = camera::toTCamera(*pinhole(32, 24));
  const auto camR = camera::toTCamera(*camera::makeCameraModel("pinhole", 32, 24, {150.0, 150.0, 16.0, 12.0}));
  ASSERT_TRUE(camL && camR);
  std::vector<cv::Mat> imL, imR;
  {
    mrpt::io::CFileGZOutputStream f(rawlog);
    auto a = mrpt::serialization::archiveFrom(f);
    for (int i = 0; i < 3; ++i)
      for (const bool isLeft : {true, false})
      {
        auto img = mrpt::obs::CObservationImage::Create();
        img->sensorLabel = isLeft ? "LEFT" : "RIGHT";
        img->timestamp = mrpt::Clock::fromDouble(2.0 + i + (isLeft ? 0.0 : 0.001));
        (isLeft ? imL : imR).push_back(syntheticImage(32, 24, CV_8UC1, (isLeft ? 0 : 50) + i));
        img->image = mrpt::img::CImage((isLeft ? imL : imR).back(), mrpt::img::DEEP_COPY);
        img->cameraParams = isLeft ? *camL : *camR;
        a << *img;
      }
  }
  const auto joined = [](const std::vector<std::string>& v) {
    std::string all;
    for (const auto& w : v) all += w + "\n";
    return all;
  };
  {
    CRawlogSource src(rawlog);
    EXPECT_NE(joined(src.warnings()).find("'LEFT' (3 images), 'RIGHT' (3 images): using 'LEFT'"), std::string::npos)
        << joined(src.warnings());
    ASSERT_TRUE(src.calibration());
    EXPECT_DOUBLE_EQ(src.calibration()->fx(), 100.0);
    const TStream s = drain(src);
    ASSERT_EQ(s.frames.size(), 3u);
    ASSERT_EQ(s.skipped.size(), 3u);
    EXPECT_NE(s.skipped[0].find("image of sensor 'RIGHT' skipped"), std::string::npos) << s.skipped[0];
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(sameImage(s.frames[i].grey, imL[i])) << i;
  }
  {
    const auto src = openImageSource(rawlog, "RIGHT");
    ASSERT_TRUE(src->calibration());
    EXPECT_DOUBLE_EQ(src->calibration()->fx(), 150.0);
    const TStream s = drain(*src);
    ASSERT_EQ(s.frames.size(), 3u);
    for (int i = 0; i < 3; ++i) EXPECT_TRUE(sameImage(s.frames[i].grey, imR[i])) << i;
  }
  try
  {
    CRawlogSource src(rawlog, "FRONT");
    ADD_FAILURE() << "no error";
  }
  catch (const std::runtime_error& e)
  {
    const std::string m = e.what();
    EXPECT_NE(m.find(rawlog), std::string::npos) << m;
    EXPECT_NE(m.find("no image of sensor 'FRONT'"), std::string::npos) << m;
    EXPECT_NE(m.find("'LEFT' (3 images), 'RIGHT' (3 images)"), std::string::npos) << m;
  }
}

TEST(Rawlog, TruncatedEndsCleanly)
{
  TempDir d;
  writeSyntheticDataset(d / "ds", 20, true, 160, 120);
  const std::string rawlog = d / "t.rawlog";
  TDataset2RawlogOptions o;
  o.embedImages = true;
  convertDatasetToRawlog(d / "ds", rawlog, o);
  const std::vector<TFrame> all = drain(*openImageSource(rawlog)).frames;
  ASSERT_EQ(all.size(), 20u);

  fs::resize_file(rawlog, fs::file_size(rawlog) * 6 / 10);
  std::unique_ptr<CRawlogSource> src;
  ASSERT_NO_THROW(src = std::make_unique<CRawlogSource>(rawlog));
  EXPECT_EQ(src->damage().rfind("rawlog truncated/corrupt after entry ", 0), 0u) << src->damage();
  const TStream s = drain(*src);
  std::cout << "[ info     ] " << s.endWhy << "\n";
  EXPECT_EQ(s.endWhy, src->damage());
  EXPECT_TRUE(s.skipped.empty());
  EXPECT_GT(s.frames.size(), 5u);
  EXPECT_LT(s.frames.size(), 20u);
  EXPECT_EQ(src->sizeHint(), s.frames.size());
  ASSERT_TRUE(src->groundTruth());  // GT poses before the damage
  EXPECT_GE(src->groundTruth()->size(), s.frames.size());
  for (std::size_t i = 0; i < s.frames.size(); ++i)
  {
    EXPECT_TRUE(sameImage(s.frames[i].colour, all[i].colour)) << i;
    EXPECT_EQ(s.frames[i].timestamp, all[i].timestamp);
  }
  // More calls after the end stay at the end.
  TFrame f;
  std::string why;
  EXPECT_EQ(src->next(f, why), ENextStatus::End);
}

TEST(Rawlog, CutBetweenObjectsDetectedByGzipTrailer)
{
  // A gzip file whose data ends exactly after object 3 of 6, without a trailer: built with zlib
  // directly (full flush after object 3, then the file is cut at that compressed offset).
  TempDir d;
  const std::string rawlog = d / "cut.rawlog";
  gzFile gz = gzopen(rawlog.c_str(), "wb");
  ASSERT_TRUE(gz);
  long cutAt = 0;
  for (int i = 0; i < 6; ++i)
  {
    mrpt::io::CMemoryStream mem;
    auto a = mrpt::serialization::archiveFrom(mem);
    auto img = mrpt::obs::CObservationImage::Create();
    img->timestamp = mrpt::Clock::fromDouble(i);
    img->image = mrpt::img::CImage(syntheticImage(16, 16, CV_8UC1, i), mrpt::img::DEEP_COPY);
    a << *img;
    ASSERT_EQ(gzwrite(gz, mem.getRawBufferData(), static_cast<unsigned>(mem.getTotalBytesCount())),
              static_cast<int>(mem.getTotalBytesCount()));
    if (i == 2)
    {
      ASSERT_EQ(gzflush(gz, Z_FULL_FLUSH), Z_OK);
      cutAt = gzoffset(gz);
    }
  }
  gzclose(gz);
  EXPECT_EQ(drain(*openImageSource(rawlog)).frames.size(), 6u);
  fs::resize_file(rawlog, static_cast<std::uintmax_t>(cutAt));
  CRawlogSource src(rawlog);
  const TStream s = drain(src);
  EXPECT_EQ(s.frames.size(), 3u);
  EXPECT_NE(s.endWhy.find("after entry 3"), std::string::npos) << s.endWhy;
  EXPECT_NE(s.endWhy.find("trailer"), std::string::npos) << s.endWhy;
}

TEST(Rawlog, CorruptBytesEndCleanly)
{
  TempDir d;
  writeSyntheticDataset(d / "ds", 10, false, 120, 90);
  const std::string rawlog = d / "c.rawlog";
  TDataset2RawlogOptions o;
  o.embedImages = true;
  o.layout = ERawlogLayout::SensoryFrames;
  convertDatasetToRawlog(d / "ds", rawlog, o);
  {
    std::fstream f(rawlog, std::ios::in | std::ios::out | std::ios::binary);
    const auto size = static_cast<long>(fs::file_size(rawlog));
    f.seekp(size / 2);
    const std::string junk(64, '\x5a');
    f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
  }
  CRawlogSource src(rawlog);
  EXPECT_FALSE(src.damage().empty());
  const TStream s = drain(src);
  EXPECT_LT(s.frames.size(), 10u);
  EXPECT_EQ(s.endWhy.rfind("rawlog truncated/corrupt after entry ", 0), 0u) << s.endWhy;
}

TEST(Rawlog, JpegImagesReadAndACorruptJpegEndsCleanly)
{
  // MRPT stores colour images as JPEG; its decoder would exit() the process on a fatal libjpeg error
  // (found by fuzzing). The reader checks each payload first: good JPEGs read, a corrupt one is damage.
  TempDir d;
  const std::string rawlog = d / "jpeg.rawlog";
  {
    const bool old = mrpt::img::CImage::DISABLE_JPEG_COMPRESSION();
    mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(false);  // (process-wide flag of MRPT)
    mrpt::io::CFileGZOutputStream f(rawlog);
    auto a = mrpt::serialization::archiveFrom(f);
    for (int i = 0; i < 4; ++i)
    {
      auto img = mrpt::obs::CObservationImage::Create();
      img->sensorLabel = "CAMERA";
      img->timestamp = mrpt::Clock::fromDouble(1.0 + i);
      img->image = mrpt::img::CImage(syntheticImage(64, 48, CV_8UC3, i), mrpt::img::DEEP_COPY);
      a << *img;
    }
    mrpt::img::CImage::DISABLE_JPEG_COMPRESSION(old);
  }
  {
    CRawlogSource src(rawlog);
    const TStream s = drain(src);
    EXPECT_EQ(s.frames.size(), 4u);
    EXPECT_EQ(s.endWhy, "");
  }
  // Uncompress, break the third JPEG's start-of-image marker (fatal for libjpeg), write it back.
  std::string bytes;
  {
    gzFile gz = gzopen(rawlog.c_str(), "rb");
    ASSERT_NE(gz, nullptr);
    char buf[4096];
    int got;
    while ((got = gzread(gz, buf, sizeof buf)) > 0) bytes.append(buf, static_cast<std::size_t>(got));
    gzclose(gz);
  }
  std::vector<std::size_t> soi;
  for (std::size_t k = 0; k + 2 < bytes.size(); ++k)
    if (static_cast<unsigned char>(bytes[k]) == 0xFF && static_cast<unsigned char>(bytes[k + 1]) == 0xD8 &&
        static_cast<unsigned char>(bytes[k + 2]) == 0xFF)
      soi.push_back(k);
  ASSERT_EQ(soi.size(), 4u);
  bytes[soi[2] + 1] = '\x00';
  const std::string broken = d / "broken.rawlog";
  std::ofstream(broken, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  CRawlogSource src(broken);
  EXPECT_NE(src.damage().find("corrupt image: not a JPEG of "), std::string::npos) << src.damage();
  const TStream s = drain(src);
  EXPECT_EQ(s.frames.size(), 2u);
  EXPECT_EQ(s.endWhy.rfind("rawlog truncated/corrupt after entry 2", 0), 0u) << s.endWhy;
}

TEST(Rawlog, NotARawlogThrowsNamingFile)
{
  TempDir d;
  const std::string p = d / "text.rawlog";
  std::ofstream(p) << "# this is a text file, not a rawlog\n1 2 3\n";
  try
  {
    openImageSource(p);
    FAIL() << "no exception";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

TEST(Rawlog, ExternalImagesMrptConventionAndMissing)
{
  // MRPT's convention: names relative to "<dir>/<rawlog name>_Images".
  TempDir d;
  fs::create_directories(d / "seq_Images");
  const cv::Mat img = syntheticImage(30, 20, CV_8UC3, 7);
  ASSERT_TRUE(cv::imwrite(d / "seq_Images/img0.png", img));
  const std::string rawlog = d / "seq.rawlog";
  {
    mrpt::io::CFileGZOutputStream f(rawlog);
    auto a = mrpt::serialization::archiveFrom(f);
    for (const char* name : {"img0.png", "img1.png"})
    {
      auto o = mrpt::obs::CObservationImage::Create();
      o->timestamp = mrpt::Clock::fromDouble(1.5);
      o->image.setExternalStorage(name);
      o->cameraParams.ncols = 30;
      o->cameraParams.nrows = 20;
      o->cameraParams.setIntrinsicParamsFromValues(20, 21, 15, 10);
      a << *o;
    }
  }
  CRawlogSource src(rawlog);
  EXPECT_EQ(src.imagesDirectory(), d / "seq_Images");
  ASSERT_TRUE(src.calibration());
  EXPECT_EQ(src.calibration()->modelName(), "pinhole");
  EXPECT_DOUBLE_EQ(src.calibration()->fy(), 21);
  const TStream s = drain(src);
  ASSERT_EQ(s.frames.size(), 1u);
  EXPECT_TRUE(sameImage(s.frames[0].colour, img));
  ASSERT_TRUE(s.frames[0].camera);
  ASSERT_EQ(s.skipped.size(), 1u);
  EXPECT_NE(s.skipped[0].find(d / "seq_Images/img1.png"), std::string::npos) << s.skipped[0];
}

TEST(Rawlog, ExternalImageUndecodableSkipped)
{
  TempDir d;
  writeSyntheticDataset(d / "ds", 3, false);
  const std::string rawlog = d / "x.rawlog";
  convertDatasetToRawlog(d / "ds", rawlog);
  std::ofstream(d / "ds/rgb/000001.png") << "garbage";
  const TStream s = drain(*openImageSource(rawlog));
  EXPECT_EQ(s.frames.size(), 2u);
  ASSERT_EQ(s.skipped.size(), 1u);
  EXPECT_NE(s.skipped[0].find("000001.png"), std::string::npos) << s.skipped[0];
}

// ------------------------------------------------------------------------------------------------
// Command line, CSV
// ------------------------------------------------------------------------------------------------

TEST(Dataset2RawlogCli, ExitCodesAndMessages)
{
  TempDir d;
  std::ostringstream out, err;
  EXPECT_EQ(dataset2rawlogCli({"--help"}, out, err), 0);
  EXPECT_NE(out.str().find("Usage"), std::string::npos);
  EXPECT_EQ(dataset2rawlogCli({}, out, err), 2);
  EXPECT_EQ(dataset2rawlogCli({"a", "b", "--layout", "xyz"}, out, err), 2);
  EXPECT_EQ(dataset2rawlogCli({"a", "b", "--bogus"}, out, err), 2);
  err.str("");
  EXPECT_EQ(dataset2rawlogCli({d / "nothing", d / "o.rawlog"}, out, err), 1);
  EXPECT_NE(err.str().find(d / "nothing"), std::string::npos) << err.str();
  writeSyntheticDataset(d / "ds", 3, true);
  out.str("");
  EXPECT_EQ(dataset2rawlogCli({d / "ds", d / "o.rawlog", "--embed", "--layout", "sf"}, out, err), 0);
  EXPECT_NE(out.str().find("3 images"), std::string::npos) << out.str();
  CRawlogSource src(d / "o.rawlog");
  EXPECT_TRUE(src.hasSensoryFrames());
  EXPECT_EQ(src.sizeHint(), 3u);
  err.str("");
  EXPECT_EQ(dataset2rawlogCli({d / "ds", d / "no_such_dir/o.rawlog"}, out, err), 1);
  EXPECT_NE(err.str().find(d / "no_such_dir/o.rawlog"), std::string::npos) << err.str();
}

TEST(CsvWriter, FormatsAndErrors)
{
  TempDir d;
  {
    CCsvWriter csv(d / "a.csv", {"timestamp", "n_map", "value", "class"});
    csv.addRow(1403715273.262143, 12, 0.1234567891234, "static");
    csv.addRow({0.5, 3.0, 1e-12, 7.0});
    csv.addRow(2.0, std::size_t(4), std::nan(""), "a,\"b\"");
    EXPECT_EQ(csv.rowCount(), 3u);
    try
    {
      csv.addRow({1.0, 2.0});
      FAIL() << "no exception";
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_NE(std::string(e.what()).find(d / "a.csv"), std::string::npos) << e.what();
    }
    csv.flush();
  }
  EXPECT_EQ(readAll(d / "a.csv"),
            "timestamp,n_map,value,class\n"
            "1403715273.262143,12,0.123456789,static\n"
            "0.500000,3,1e-12,7\n"
            "2.000000,4,nan,\"a,\"\"b\"\"\"\n");
  try
  {
    CCsvWriter bad(d / "missing_dir/x.csv", {"timestamp"});
    FAIL() << "no exception";
  }
  catch (const std::runtime_error& e)
  {
    EXPECT_NE(std::string(e.what()).find(d / "missing_dir/x.csv"), std::string::npos) << e.what();
  }
}

TEST(OpenImageSource, ChoosesByPathKind)
{
  TempDir d;
  writeSyntheticDataset(d / "ds", 2, false);
  auto a = openImageSource(d / "ds");
  EXPECT_NE(dynamic_cast<CDatasetFolderSource*>(a.get()), nullptr);
  EXPECT_NE(a->describe().find("2 frames"), std::string::npos) << a->describe();
  convertDatasetToRawlog(d / "ds", d / "r.rawlog");
  auto b = openImageSource(d / "r.rawlog");
  EXPECT_NE(dynamic_cast<CRawlogSource*>(b.get()), nullptr);
  EXPECT_EQ(b->sizeHint(), 2u);
  EXPECT_NE(b->describe().find("rawlog"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// Video files
// ---------------------------------------------------------------------------------------------
TEST(VideoFile, FramesTimestampsAndColourOfAVideoOpenedByItsExtension)
{
  TempDir d;
  const std::string path = d / "clip.AVI";  // the extension decides, in any case
  {
    cv::VideoWriter w(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25.0, {64, 48}, true);
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 7; ++i) w.write(cv::Mat(48, 64, CV_8UC3, cv::Scalar(20 * i, 100, 200 - 20 * i)));
  }
  EXPECT_TRUE(isVideoFile(path));
  EXPECT_TRUE(isVideoFile("a/b/c.mp4"));
  EXPECT_FALSE(isVideoFile("a/b/c.rawlog"));
  EXPECT_FALSE(isVideoFile("a/b/mp4"));
  const auto src = openImageSource(path);
  ASSERT_NE(dynamic_cast<CVideoFileSource*>(src.get()), nullptr);
  EXPECT_EQ(src->calibration(), nullptr) << "a video carries no calibration";
  EXPECT_NE(src->describe().find(path), std::string::npos) << src->describe();
  EXPECT_EQ(src->sizeHint(), 7u);
  const TStream s = drain(*src);
  ASSERT_EQ(s.frames.size(), 7u);
  EXPECT_TRUE(s.skipped.empty());
  EXPECT_EQ(s.endWhy, "");
  for (std::size_t i = 0; i < s.frames.size(); ++i)
  {
    EXPECT_EQ(s.frames[i].index, i);
    EXPECT_NEAR(s.frames[i].timestamp, i / 25.0, 1e-9);
    EXPECT_EQ(s.frames[i].grey.type(), CV_8UC1);
    EXPECT_EQ(s.frames[i].colour.type(), CV_8UC3);
    EXPECT_EQ(s.frames[i].grey.cols, 64);
  }
  // A given frame rate overrides the container's.
  CVideoFileSource at10(path, 10.0);
  TFrame f;
  std::string why;
  ASSERT_EQ(at10.next(f, why), ENextStatus::Frame);
  ASSERT_EQ(at10.next(f, why), ENextStatus::Frame);
  EXPECT_NEAR(f.timestamp, 0.1, 1e-12);
}

TEST(VideoFile, ACutVideoEndsCleanlyAndSaysSo)
{
  // A video cut in the middle (a copy interrupted, a download stopped): the frames up to the cut are
  // read, and the end says how many of the frames its header announces were there.
  TempDir d;
  const std::string path = d / "cut.avi";
  {
    cv::VideoWriter w(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25.0, {64, 48}, true);
    ASSERT_TRUE(w.isOpened());
    for (int i = 0; i < 60; ++i) w.write(syntheticImage(64, 48, CV_8UC3, i));
  }
  EXPECT_EQ(drain(*openImageSource(path), false).endWhy, "");  // whole: a normal end
  fs::resize_file(path, fs::file_size(path) / 2);
  std::unique_ptr<CImageSource> src;
  try
  {
    src = openImageSource(path);
  }
  catch (const std::runtime_error& e)
  {
    GTEST_SKIP() << "this OpenCV does not open a cut AVI: " << e.what();
  }
  const std::size_t announced = src->sizeHint();
  const TStream s = drain(*src, false);
  std::cout << "[ info     ] " << s.frames.size() << " frames read; end: " << s.endWhy << "\n";
  EXPECT_GT(s.frames.size(), 10u);
  EXPECT_LT(s.frames.size(), 60u);
  if (announced == 60u)
  {
    EXPECT_NE(s.endWhy.find("ended after " + std::to_string(s.frames.size()) + " of the 60 frames"), std::string::npos)
        << s.endWhy;
    EXPECT_NE(s.endWhy.find(path), std::string::npos) << s.endWhy;
  }
}

TEST(VideoFile, MissingOrUndecodableVideoIsAnErrorNamingIt)
{
  TempDir d;
  const std::string bad = d / "notes.mp4";
  std::ofstream(bad) << "not a video\n";
  for (const std::string& p : {bad, d / "missing.mkv"})
  {
    try
    {
      openImageSource(p);
      ADD_FAILURE() << "no exception for " << p;
    }
    catch (const std::runtime_error& e)
    {
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
    }
  }
}
