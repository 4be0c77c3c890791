/* The fuzz targets on every committed seed (corpus/<target>/) and every input that once made a
 * target fail (regressions/<target>/): a normal ctest test in every build, so a fixed crash stays
 * fixed. Also writes the generated rawlog seeds (DISABLED_WriteRawlogSeeds, run by hand). */
#include "fuzz_targets.h"

#include <gtest/gtest.h>

#include <mrpt/core/Clock.h>
#include <mrpt/img/CImage.h>
#include <mrpt/img/TCamera.h>
#include <mrpt/io/CFileGZOutputStream.h>
#include <mrpt/io/CFileOutputStream.h>
#include <mrpt/obs/CActionCollection.h>
#include <mrpt/obs/CObservationComment.h>
#include <mrpt/obs/CObservationImage.h>
#include <mrpt/obs/CObservationOdometry.h>
#include <mrpt/obs/CObservationRobotPose.h>
#include <mrpt/obs/CSensoryFrame.h>
#include <mrpt/serialization/CArchive.h>

#include <opencv2/core.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;
using namespace immslam;

namespace
{
std::string readBytes(const fs::path& p)
{
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/** Runs a target on every file of corpus/<name>/ and regressions/<name>/; returns how many. */
std::size_t runAll(const fuzz::TFuzzTarget& t)
{
  std::size_t n = 0;
  for (const char* kind : {"corpus", "regressions"})
  {
    const fs::path dir = fs::path(IMMSLAM_FUZZ_DIR) / kind / t.name;
    if (!fs::is_directory(dir)) continue;
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir))
      if (e.is_regular_file() && e.path().filename().string()[0] != '.') files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& p : files)
    {
      SCOPED_TRACE(p.string());
      const std::string bytes = readBytes(p);
      EXPECT_EQ(t.run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), 0);
      ++n;
    }
  }
  return n;
}

class FuzzRegression : public testing::TestWithParam<fuzz::TFuzzTarget>
{
};
}  // namespace

TEST_P(FuzzRegression, SeedsAndFormerCrashesRunCleanly)
{
  const std::size_t n = runAll(GetParam());
  std::printf("[ info     ] %s: %zu inputs\n", GetParam().name, n);
  EXPECT_GT(n, 0u) << "no seed for target " << GetParam().name;
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzRegression, testing::ValuesIn(fuzz::fuzzTargets()),
                         [](const testing::TestParamInfo<fuzz::TFuzzTarget>& i) { return std::string(i.param.name); });

TEST(FuzzRegression, EmptyAndTinyInputs)
{
  for (const auto& t : fuzz::fuzzTargets())
    for (const std::string& s : {std::string(), std::string("\n"), std::string(1, '\0'), std::string("%%\n%%\n")})
      EXPECT_EQ(t.run(reinterpret_cast<const std::uint8_t*>(s.data()), s.size()), 0) << t.name;
}

// Writes the generated rawlog seeds into the source tree (tests/fuzz/corpus/rawlog/). Run by hand:
//   fuzz_regression_unittest --gtest_also_run_disabled_tests --gtest_filter='*WriteRawlogSeeds'
TEST(FuzzSeeds, DISABLED_WriteRawlogSeeds)
{
  const fs::path dir = fs::path(IMMSLAM_FUZZ_DIR) / "corpus" / "rawlog";
  fs::create_directories(dir);
  const auto image = [](int i, bool withCamera) {
    auto o = mrpt::obs::CObservationImage::Create();
    o->sensorLabel = "CAMERA";
    o->timestamp = mrpt::Clock::fromDouble(10.0 + i / 30.0);
    cv::Mat m(6, 8, CV_8UC1);
    for (int k = 0; k < 48; ++k) m.data[k] = static_cast<uchar>(k * 5 + i);
    o->image = mrpt::img::CImage(m, mrpt::img::DEEP_COPY);
    if (withCamera)
    {
      o->cameraParams.ncols = 8;
      o->cameraParams.nrows = 6;
      o->cameraParams.setIntrinsicParamsFromValues(6, 6, 3.5, 2.5);
    }
    return o;
  };
  // Uncompressed files: the fuzzer mutates the MRPT objects directly.
  {
    mrpt::io::CFileOutputStream f((dir / "plain_images.rawlog").string());
    auto a = mrpt::serialization::archiveFrom(f);
    for (int i = 0; i < 2; ++i) a << *image(i, i == 0);
  }
  {
    mrpt::io::CFileOutputStream f((dir / "plain_sensory_frames.rawlog").string());
    auto a = mrpt::serialization::archiveFrom(f);
    for (int i = 0; i < 2; ++i)
    {
      mrpt::obs::CActionCollection acts;
      mrpt::obs::CSensoryFrame sf;
      sf.insert(image(i, true));
      a << acts << sf;
    }
  }
  {
    mrpt::io::CFileOutputStream f((dir / "plain_mixed.rawlog").string());
    auto a = mrpt::serialization::archiveFrom(f);
    a << *image(0, true);
    auto odo = mrpt::obs::CObservationOdometry::Create();
    odo->sensorLabel = "ODOMETRY";
    a << *odo;
    auto gt = mrpt::obs::CObservationRobotPose::Create();
    gt->sensorLabel = "GT";
    gt->timestamp = mrpt::Clock::fromDouble(10.0);
    gt->pose.mean = mrpt::poses::CPose3D(1, 2, 3, 0.1, 0.2, 0.3);
    a << *gt;
    auto c = mrpt::obs::CObservationComment::Create();
    c->text = "seed";
    a << *c;
  }
  {
    mrpt::io::CFileOutputStream f((dir / "plain_external.rawlog").string());
    auto a = mrpt::serialization::archiveFrom(f);
    auto o = image(0, false);
    o->image.setExternalStorage("missing_image.png");
    a << *o;
  }
  {
    mrpt::io::CFileGZOutputStream f((dir / "gz_images.rawlog").string());
    auto a = mrpt::serialization::archiveFrom(f);
    for (int i = 0; i < 2; ++i) a << *image(i, true);
  }
  for (const auto& e : fs::directory_iterator(dir)) std::printf("%s: %zu bytes\n", e.path().c_str(), fs::file_size(e));
}
