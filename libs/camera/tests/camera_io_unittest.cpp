/* Tests: calib.txt parsing/loading/saving, MRPT TCamera conversions and config sections. */
#include "test_cameras.h"

#include <gtest/gtest.h>
#include <immslam/camera/mrpt_camera.h>
#include <mrpt/config/CConfigFileMemory.h>
#include <mrpt/img/TCamera.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>

using namespace immslam;
using namespace immslam::camera;
namespace fs = std::filesystem;

namespace
{
/** The message of the std::runtime_error thrown by f ("" if none). */
template <typename F>
std::string errorOf(F&& f)
{
  try
  {
    f();
  }
  catch (const std::runtime_error& e)
  {
    return e.what();
  }
  return "";
}

/** A fresh temporary folder removed at the end of the test. */
class CTempDir
{
 public:
  CTempDir()
  {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    m_path = fs::temp_directory_path() /
             ("immslam_camera_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(m_path);
    fs::create_directories(m_path);
  }
  ~CTempDir() { fs::remove_all(m_path); }
  std::string write(const std::string& name, const std::string& content) const
  {
    const std::string p = (m_path / name).string();
    std::ofstream(p) << content;
    return p;
  }
  std::string path(const std::string& name) const { return (m_path / name).string(); }

 private:
  fs::path m_path;
};

void expectSameModel(const CCameraModel& a, const CCameraModel& b)
{
  EXPECT_EQ(a.modelName(), b.modelName());
  EXPECT_EQ(a.width(), b.width());
  EXPECT_EQ(a.height(), b.height());
  EXPECT_EQ(a.parameters(), b.parameters());
}

const char* kSection = "[CAMERA_PARAMS]\n";
}  // namespace

TEST(CalibFile, ParsesEveryModel)
{
  auto c = parseCalibLine("pinhole 320 240 170 170 160 120", "x");
  EXPECT_EQ(c->modelName(), "pinhole");
  EXPECT_EQ(c->parameters(), (std::vector<double>{170, 170, 160, 120}));
  c = parseCalibLine("  opencv\t752 480 458.654 457.296 367.215 248.375 -0.28340811 0.07395907 "
                     "0.00019359 1.76187114e-05 0  # EuRoC cam0",
      "x");
  expectSameModel(*c, *test::eurocCamera());
  c = parseCalibLine("davison 320 240 195 195 162 125 9e-06", "x");
  expectSameModel(*c, *test::monoslamCamera());
}

TEST(CalibFile, MalformedLinesAreRejectedWithContext)
{
  const std::map<std::string, std::string> cases = {
      {"", "empty calibration line"},
      {"   # only a comment", "empty calibration line"},
      {"fishye 320 240 170 170 160 120", "unknown camera model 'fishye'"},
      {"fisheye 320 240 170 170 160 120", "needs 10 values"},
      {"pinhole 320 240 170 170 160", "needs 6 values after the model name"},
      {"pinhole 320 240 170 170 160 120 7", "got 7"},
      {"opencv 752 480 458 457 367 248 -0.28 0.07 0.0001 0.00001", "needs 11 values"},
      {"davison 320 240 195 195 162 125", "needs 7 values"},
      {"pinhole 320 240 abc 170 160 120", "fx = 'abc' is not a number"},
      {"pinhole 320 240 170 170 160 120x", "cy = '120x' is not a number"},
      {"pinhole 320 240 170 170 1,5 120", "cx = '1,5' is not a number"},
      {"opencv 752 480 458 457 367 248 -0.28 0.07 0.0001 nan 0", "p2 = 'nan' is not finite"},
      {"pinhole 0 240 170 170 160 120", "width must be a positive integer, got '0'"},
      {"pinhole 320.5 240 170 170 160 120", "width must be a positive integer, got '320.5'"},
      {"pinhole 320 -240 170 170 160 120", "height must be a positive integer"},
      {"pinhole 320 240 -170 170 160 120", "fx must be positive"},
      {"davison 320 240 195 0 162 125 9e-6", "fy must be positive"},
  };
  for (const auto& [line, expected] : cases)
  {
    const std::string msg = errorOf([&] { parseCalibLine(line, "calib.txt:3"); });
    EXPECT_NE(msg.find("calib.txt:3"), std::string::npos) << line << " -> " << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << line << " -> " << msg;
  }
}

TEST(CalibFile, MakeCameraModelChecksNameAndCount)
{
  EXPECT_EQ(makeCameraModel("davison", 320, 240, {195, 195, 162, 125, 9e-6})->modelName(), "davison");
  EXPECT_NE(errorOf([] { makeCameraModel("kb4", 320, 240, {1, 1, 1, 1}); }).find("'kb4'"), std::string::npos);
  EXPECT_NE(errorOf([] { makeCameraModel("opencv", 320, 240, {1, 1, 1, 1}); }).find("needs 9"),
      std::string::npos);
  EXPECT_NE(errorOf([] { makeCameraModel("pinhole", 320, 0, {1, 1, 1, 1}); }).find("height"),
      std::string::npos);
}

TEST(CalibFile, LoadSkipsCommentsAndNamesFileAndLine)
{
  CTempDir dir;
  const std::string good = dir.write("good.txt",
      "# model width height fx fy cx cy kd1\n\n   \n# another comment\r\n"
      "davison 320 240 195 195 162 125 9e-06   # trailing comment\r\n\n");
  expectSameModel(*loadCalibFile(good), *test::monoslamCamera());

  const std::string two = dir.write("two.txt", "# c\npinhole 320 240 170 170 160 120\n\n# c\npinhole 1 1 1 1 0 0\n");
  std::string msg = errorOf([&] { loadCalibFile(two); });
  EXPECT_NE(msg.find(two + ":5"), std::string::npos) << msg;
  EXPECT_NE(msg.find("line 2"), std::string::npos) << msg;

  const std::string bad = dir.write("bad.txt", "# c\n\n\nopencv 752 480 458 457 367 248 -0.28 0.07\n");
  msg = errorOf([&] { loadCalibFile(bad); });
  EXPECT_NE(msg.find(bad + ":4"), std::string::npos) << msg;
  EXPECT_NE(msg.find("needs 11 values"), std::string::npos) << msg;

  const std::string none = dir.write("none.txt", "# nothing here\n\n");
  msg = errorOf([&] { loadCalibFile(none); });
  EXPECT_NE(msg.find(none), std::string::npos) << msg;
  EXPECT_NE(msg.find("no model line"), std::string::npos) << msg;

  msg = errorOf([&] { loadCalibFile(dir.path("missing.txt")); });
  EXPECT_NE(msg.find("missing.txt"), std::string::npos) << msg;
}

TEST(CalibFile, SaveLoadRoundTripIsExact)
{
  CTempDir dir;
  for (const auto& tc : test::testCameras())
    for (const CCameraModel::Ptr& cam : {tc.cam, tc.cam->scaled(0.7)})
    {
      const std::string p = dir.path(tc.name + ".txt");
      saveCalibFile(*cam, p);
      std::ifstream f(p);
      std::string first;
      std::getline(f, first);
      EXPECT_EQ(first.rfind("# model width height fx fy cx cy", 0), 0u) << first;
      expectSameModel(*loadCalibFile(p), *cam);
    }
  EXPECT_THROW(saveCalibFile(*test::eurocCamera(), dir.path("no/such/dir/calib.txt")), std::runtime_error);
}

TEST(CalibFile, SharedDataCalibrationsLoad)
{
  const fs::path data(IMMSLAM_SHARED_DATA_DIR);
  if (!fs::is_directory(data)) GTEST_SKIP() << "shared data folder " << data << " is absent";
  struct TExpect
  {
    const char* folder;
    const char* model;
    int w, h;
  };
  const TExpect sets[] = {{"euroc_v101_stationary", "opencv", 752, 480},
      {"monoslam_testseq", "davison", 320, 240}, {"monoslammot_synth19", "pinhole", 320, 240},
      {"visp_rbt", "pinhole", 640, 480}};
  const auto hardCoded = test::testCameras();
  for (const auto& s : sets)
  {
    const fs::path p = data / s.folder / "calib.txt";
    if (!fs::exists(p))
    {
      ADD_FAILURE() << p << " missing";
      continue;
    }
    const CCameraModel::Ptr cam = loadCalibFile(p.string());
    EXPECT_EQ(cam->modelName(), s.model) << p;
    EXPECT_EQ(cam->width(), s.w) << p;
    EXPECT_EQ(cam->height(), s.h) << p;
    // The tests' hard-coded parameter sets are these calibrations.
    bool found = false;
    for (const auto& tc : hardCoded) found = found || tc.cam->toCalibLine() == cam->toCalibLine();
    EXPECT_TRUE(found) << p << ": " << cam->toCalibLine();
  }
}

TEST(MrptCamera, TCameraRoundTrip)
{
  const CCameraModel::Ptr pinhole = test::testCameras()[0].cam;
  const auto tp = toTCamera(*pinhole);
  ASSERT_TRUE(tp.has_value());
  EXPECT_EQ(tp->ncols, 640u);
  EXPECT_EQ(tp->distortion, mrpt::img::DistortionModel::none);
  EXPECT_EQ(tp->fy(), pinhole->fy());
  expectSameModel(*fromTCamera(*tp), *pinhole);

  const auto euroc = test::eurocCamera();
  const auto te = toTCamera(*euroc);
  ASSERT_TRUE(te.has_value());
  EXPECT_EQ(te->distortion, mrpt::img::DistortionModel::plumb_bob);
  EXPECT_EQ(te->k1(), euroc->k1());
  EXPECT_EQ(te->p2(), euroc->p2());
  EXPECT_EQ(te->cx(), euroc->cx());
  expectSameModel(*fromTCamera(*te), *euroc);
  expectSameModel(*fromTCamera(*toTCamera(*test::strongOpenCVCamera())), *test::strongOpenCVCamera());

  // Fisheye <-> kannala_brandt: MRPT keeps k3 k4 in dist[4], dist[5] (its k3(), k4()).
  const auto tumvi = test::tumviCamera();
  const auto tf = toTCamera(*tumvi);
  ASSERT_TRUE(tf.has_value());
  EXPECT_EQ(tf->distortion, mrpt::img::DistortionModel::kannala_brandt);
  EXPECT_EQ(tf->k3(), tumvi->k3());
  EXPECT_EQ(tf->dist[5], tumvi->k4());
  expectSameModel(*fromTCamera(*tf), *tumvi);

  EXPECT_FALSE(toTCamera(*test::monoslamCamera()).has_value());
}

TEST(MrptCamera, FromTCameraEdgeCases)
{
  mrpt::img::TCamera t;
  t.ncols = 640;
  t.nrows = 480;
  t.setIntrinsicParamsFromValues(500, 501, 320, 240);
  t.setDistortionPlumbBob(0, 0, 0, 0, 0);
  EXPECT_EQ(fromTCamera(t)->modelName(), "pinhole");
  t.distortion = mrpt::img::DistortionModel::none;
  t.k1(-0.2);  // ignored with distortion = none, as MRPT does
  EXPECT_EQ(fromTCamera(t)->modelName(), "pinhole");
  t.distortion = mrpt::img::DistortionModel::plumb_bob;
  EXPECT_EQ(fromTCamera(t)->modelName(), "opencv");
  t.k4(0.01);
  EXPECT_NE(errorOf([&] { fromTCamera(t); }).find("k4"), std::string::npos);
  t.setDistortionKannalaBrandt(0.1, -0.02, 0.003, -0.0004);
  const auto fe = fromTCamera(t);
  EXPECT_EQ(fe->modelName(), "fisheye");
  EXPECT_EQ(fe->parameters(), (std::vector<double>{500, 501, 320, 240, 0.1, -0.02, 0.003, -0.0004}));
  const auto back = toTCamera(*fe);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->distortion, mrpt::img::DistortionModel::kannala_brandt);
  EXPECT_EQ(back->getDistortionParamsAsVector(), (std::vector<double>{0.1, -0.02, 0.003, -0.0004}));
  mrpt::img::TCamera zero;  // all zero
  EXPECT_THROW(fromTCamera(zero), std::runtime_error);
  zero.ncols = 0;
  EXPECT_THROW(fromTCamera(zero), std::runtime_error);
}

TEST(MrptCamera, LoadsConfigSectionVariants)
{
  using mrpt::config::CConfigFileMemory;
  const std::string base =
      std::string(kSection) + "resolution = [752 480]\nfx = 458.654\nfy = 457.296\ncx = 367.215\ncy = 248.375\n";
  const std::string eurocDist = "dist = [-0.28340811 0.07395907 0.00019359 1.76187114e-05 0]\n";

  // MRPT camera-calib style (plumb_bob).
  auto cam = loadCameraFromConfig(CConfigFileMemory(base + "distortion_model = plumb_bob\n" + eurocDist), "CAMERA_PARAMS");
  expectSameModel(*cam, *test::eurocCamera());
  // MRPT 1.x style: dist without distortion_model, commas accepted.
  cam = loadCameraFromConfig(CConfigFileMemory(base + "dist = [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0]\n"), "CAMERA_PARAMS");
  expectSameModel(*cam, *test::eurocCamera());
  // Our extension: model = opencv, 8 coefficients with zero k4..k6.
  cam = loadCameraFromConfig(CConfigFileMemory(base + "model = opencv\ndist = [-0.28340811 0.07395907 0.00019359 1.76187114e-05 0 0 0 0]\n"), "CAMERA_PARAMS");
  expectSameModel(*cam, *test::eurocCamera());
  // No distortion at all, distortion_model = none (dist ignored), zero plumb_bob: pinhole.
  EXPECT_EQ(loadCameraFromConfig(CConfigFileMemory(base), "CAMERA_PARAMS")->modelName(), "pinhole");
  EXPECT_EQ(loadCameraFromConfig(CConfigFileMemory(base + "distortion_model = none\n" + eurocDist), "CAMERA_PARAMS")->modelName(), "pinhole");
  EXPECT_EQ(loadCameraFromConfig(CConfigFileMemory(base + "distortion_model = plumb_bob\ndist = [0 0 0 0 0]\n"), "CAMERA_PARAMS")->modelName(), "pinhole");
  cam = loadCameraFromConfig(CConfigFileMemory(base + "model = pinhole\ncamera_name = cam0 // ignored\n"), "CAMERA_PARAMS");
  EXPECT_EQ(cam->parameters(), (std::vector<double>{458.654, 457.296, 367.215, 248.375}));
  // Davison.
  cam = loadCameraFromConfig(CConfigFileMemory(std::string(kSection) +
      "model = davison\nresolution = [320 240]\nfx = 195\nfy = 195\ncx = 162\ncy = 125\nkd1 = 9e-06\n"), "CAMERA_PARAMS");
  expectSameModel(*cam, *test::monoslamCamera());
  // MRPT's fractional intrinsics (values < 2 are fractions of the image size).
  cam = loadCameraFromConfig(CConfigFileMemory(std::string(kSection) +
      "resolution = [640 480]\nfx = 0.75\nfy = 1.0\ncx = 0.5\ncy = 0.5\n"), "CAMERA_PARAMS");
  EXPECT_EQ(cam->parameters(), (std::vector<double>{480, 480, 320, 240}));

  // calib_file takes precedence over every other key.
  CTempDir dir;
  const std::string calib = dir.write("calib.txt", "davison 320 240 195 195 162 125 9e-06\n");
  cam = loadCameraFromConfig(CConfigFileMemory(base + eurocDist + "model = opencv\ncalib_file = " + calib + "\n"), "CAMERA_PARAMS");
  expectSameModel(*cam, *test::monoslamCamera());
  const std::string msg = errorOf([&] {
    loadCameraFromConfig(CConfigFileMemory(std::string(kSection) + "calib_file = " + dir.path("nope.txt") + "\n"), "CAMERA_PARAMS");
  });
  EXPECT_NE(msg.find("calib_file"), std::string::npos) << msg;
  EXPECT_NE(msg.find("nope.txt"), std::string::npos) << msg;
}

TEST(MrptCamera, ReadsSectionsWrittenByMrpt)
{
  for (const CCameraModel::Ptr& cam : {test::testCameras()[0].cam, CCameraModel::Ptr(test::eurocCamera()), CCameraModel::Ptr(test::tumviCamera())})
  {
    mrpt::config::CConfigFileMemory cfg;
    toTCamera(*cam)->saveToConfigFile("CAMERA_PARAMS", cfg);
    const CCameraModel::Ptr back = loadCameraFromConfig(cfg, "CAMERA_PARAMS");
    EXPECT_EQ(back->modelName(), cam->modelName()) << cfg.getContent();
    EXPECT_EQ(back->width(), cam->width());
    const auto a = back->parameters(), b = cam->parameters();
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) EXPECT_NEAR(a[i], b[i], 1e-5 + 1e-6 * std::abs(b[i])) << i;
  }
}

TEST(MrptCamera, ConfigErrorsNameSectionAndKey)
{
  using mrpt::config::CConfigFileMemory;
  const std::map<std::string, std::string> keys = {{"resolution", "[640 480]"}, {"fx", "500"},
      {"fy", "500"}, {"cx", "320"}, {"cy", "240"}};
  // Each required key missing in turn.
  for (const auto& [missing, unused] : keys)
  {
    std::string text = kSection;
    for (const auto& [k, v] : keys)
      if (k != missing) text += k + " = " + v + "\n";
    const std::string msg = errorOf([&] { loadCameraFromConfig(CConfigFileMemory(text), "CAMERA_PARAMS"); });
    EXPECT_NE(msg.find("[CAMERA_PARAMS]"), std::string::npos) << msg;
    EXPECT_NE(msg.find("missing key '" + missing + "'"), std::string::npos) << msg;
  }
  const std::string base = std::string(kSection) + "resolution = [640 480]\nfx = 500\nfy = 500\ncx = 320\ncy = 240\n";
  const std::map<std::string, std::string> cases = {
      {"model = davison\n", "missing key 'kd1'"},
      {"model = opencv\n", "missing key 'dist'"},
      {"distortion_model = plumb_bob\n", "missing key 'dist'"},
      {"model = davison\nkd1 = x\n", "key 'kd1': 'x' is not a number"},
      {"model = fishye\n", "key 'model': unknown value 'fishye'"},
      {"model = fisheye\n", "missing key 'dist'"},
      {"distortion_model = kannala_brandt\n", "missing key 'dist'"},
      {"distortion_model = kannala_brandt\ndist = [0.1 0 0 0 0]\n", "key 'dist': expected 4 coefficients"},
      {"model = pinhole\ndist = [0.1 0 0 0 0]\n", "key 'dist'"},
      {"dist = [0.1 0 0]\n", "key 'dist': expected 4, 5 or 8"},
      {"dist = [0.1 0 0 0 0 0.2 0 0]\n", "k4 k5 k6"},
      {"dist = [0.1 zz 0 0 0]\n", "key 'dist': 'zz' is not a number"},
      {"distortion_model = equidistant\n", "key 'distortion_model': unknown value"},
  };
  for (const auto& [extra, expected] : cases)
  {
    const std::string msg = errorOf([&] { loadCameraFromConfig(CConfigFileMemory(base + extra), "CAMERA_PARAMS"); });
    EXPECT_NE(msg.find("[CAMERA_PARAMS]"), std::string::npos) << extra << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << extra << " -> " << msg;
  }
  const std::map<std::string, std::string> badValues = {{"fx = abc\n", "key 'fx': 'abc'"},
      {"fx = -500\n", "fx must be positive"}, {"resolution = [640]\n", "key 'resolution'"},
      {"resolution = [640 0]\n", "key 'resolution'"}, {"resolution = [640.5 480]\n", "key 'resolution'"}};
  for (const auto& [line, expected] : badValues)
  {
    std::string text = std::string(kSection) + line;
    for (const auto& [k, v] : keys)
      if (line.rfind(k + " ", 0) != 0) text += k + " = " + v + "\n";
    const std::string msg = errorOf([&] { loadCameraFromConfig(CConfigFileMemory(text), "CAMERA_PARAMS"); });
    EXPECT_NE(msg.find("[CAMERA_PARAMS]"), std::string::npos) << line << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << line << " -> " << msg;
  }
  const std::string msg = errorOf([&] { loadCameraFromConfig(CConfigFileMemory(base), "NOPE"); });
  EXPECT_NE(msg.find("[NOPE] not found"), std::string::npos) << msg;
  EXPECT_EQ(cameraConfigKeys().size(), 12u);
}

TEST(CalibFile, PinholeFromFieldOfView)
{
  // 90 degrees over 640 px: f = 320; a ray 45 degrees to the right meets the image's right edge.
  const auto cam = camera::pinholeFromFieldOfView(640, 480, 90);
  EXPECT_EQ(cam->modelName(), "pinhole");
  EXPECT_NEAR(cam->fx(), 320, 1e-9);
  EXPECT_NEAR(cam->fy(), 320, 1e-9);
  Vec2 uv;
  ASSERT_TRUE(cam->project(Vec3(1, 0, 1), uv));
  EXPECT_NEAR(uv.x(), 639.5, 1e-9);
  EXPECT_NEAR(uv.y(), 239.5, 1e-9);
  EXPECT_THROW(camera::pinholeFromFieldOfView(0, 480, 60), std::invalid_argument);
  EXPECT_THROW(camera::pinholeFromFieldOfView(640, 480, 0.5), std::invalid_argument);
  EXPECT_THROW(camera::pinholeFromFieldOfView(640, 480, 180), std::invalid_argument);
}
