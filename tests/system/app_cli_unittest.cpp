/* The command line of CONTRACT.md: usage errors, config errors naming the key, --help/--version. */
#include "test_helpers.h"

#include <immslam/app/app_options.h>
#include <immslam/camera/CCameraModel.h>
#include <immslam/core/config.h>
#include <immslam/system/CMonoSlamSystem.h>

#include <mrpt/config/CConfigFile.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>

using namespace immslam;
using namespace immslam::test;

TEST(AppCli, UsageAndHelp)
{
  EXPECT_EQ(runApp({"--help"}), 0);
  EXPECT_EQ(runApp({"--version"}), 0);
  EXPECT_EQ(runApp({}), 2);
  EXPECT_EQ(runApp({"a.ini", "b", "c"}), 2);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "--frames"}), 2);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "--frames", "x"}), 2);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "--bogus"}), 2);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "--set", "nodot"}), 2);
}

TEST(AppConfig, CodeDefaultsAreTheRecommendedConfiguration)
{
  // ini/imm7-shadow.ini only names its defining keys: every estimator key at its code default gives the
  // same effective configuration as the shipped file.
  mrpt::config::CConfigFile shipped(sourceDir() + "/ini/imm7-shadow.ini");
  mrpt::config::CConfigFileMemory empty(""), fromDefaults, fromShipped;
  system::CMonoSlamSystem::effectiveConfig(empty, fromDefaults);
  system::CMonoSlamSystem::effectiveConfig(shipped, fromShipped);
  std::string a, b;
  fromDefaults.getContent(a);
  fromShipped.getContent(b);
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, b);
  // The internal constants that replaced removed keys are the options' defaults (the library's defaults
  // are the configuration's).
  const slam::CSlamTracker::TOptions so;
  EXPECT_EQ(so.adaptive_noise_rate, so.kAdaptiveNoiseRate);
  EXPECT_EQ(so.delete_min_predictions, so.kDeleteMinPredictions);
  EXPECT_EQ(so.relocalise_max_frames, so.kRelocaliseMaxFrames);
  EXPECT_EQ(slam::TIMMBankOptions().transition_stay, slam::TIMMBankOptions::kTransitionStay);
  EXPECT_EQ(slam::COnePointRansac::TOptions().max_hypotheses, slam::COnePointRansac::TOptions::kMaxHypotheses);
  const shadow::CShadowFilter::TOptions sh;
  EXPECT_EQ(sh.alpha, sh.kAlpha);
  EXPECT_EQ(sh.static_power, sh.kStaticPower);
  EXPECT_EQ(sh.max_pending_frames, sh.kMaxPendingFrames);
}

TEST(AppConfig, RemovedKeysNameWhatReplacedThem)
{
  // The sections the application reads: the system's, and its own [input] and [output].
  auto known = system::CMonoSlamSystem::knownKeys();
  known["input"] = core::knownKeys(app::TInputOptions(), "input");
  known["output"] = core::knownKeys(app::TOutputOptions(), "output");
  for (const auto& [key, why] : system::CMonoSlamSystem::removedKeys())
  {
    EXPECT_TRUE(why.rfind("removed", 0) == 0 || why.rfind("moved to [", 0) == 0) << key << ": " << why;
    const auto section = key.substr(1, key.find(']') - 1);
    const auto name = key.substr(key.find(']') + 2);
    ASSERT_TRUE(known.count(section)) << key;
    EXPECT_EQ(known.at(section).count(name), 0u) << key << " is still a key";
  }
  EXPECT_GE(system::CMonoSlamSystem::removedKeys().size(), 50u);
  // The tuning internals made constants (issue 28: about 60 keys, each one a user would turn).
  for (const char* key : {"[slam] adaptive_noise_rate", "[slam] min_sigma_pixel", "[slam] init_linear_velocity_std_px",
                          "[slam] expand_search_factor", "[slam] min_shi_tomasi", "[slam] delete_min_match_ratio",
                          "[slam] linearity_threshold", "[slam] relocalise_patience", "[imm] transition_stay",
                          "[imm] probability_floor", "[ransac] max_hypotheses", "[shadow] alpha",
                          "[shadow] static_power", "[shadow] dynamic_max_missed_frames"})
  {
    ASSERT_TRUE(system::CMonoSlamSystem::removedKeys().count(key)) << key;
    EXPECT_EQ(system::CMonoSlamSystem::removedKeys().at(key).rfind("removed: internal constant (", 0) == 0 ||
                  system::CMonoSlamSystem::removedKeys().at(key).find("transition_matrix") != std::string::npos,
              true)
        << key;
  }
  std::size_t keys = 0;
  for (const auto& [section, names] : system::CMonoSlamSystem::knownKeys()) keys += names.size();
  EXPECT_LE(keys, 40u) << "estimator keys ([input] and [output] aside)";
  // An old config with a removed internal stops naming the key and what replaced it.
  const std::string dir = outDir("removed_internal");
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/old.ini") << "[shadow]\nalpha = 0.05\n";
  testing::internal::CaptureStderr();
  EXPECT_EQ(runApp({dir + "/old.ini", "--out", dir + "/out"}), 1);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find(dir + "/old.ini: [shadow] alpha: removed: internal constant (0.05"), std::string::npos) << err;
}

TEST(AppCli, BadConfigAndInputExitWithOne)
{
  testing::internal::CaptureStderr();
  EXPECT_EQ(runApp({"/nonexistent/config.ini"}), 1);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "--set", "slam.sigma_pixle=1", "--out", outDir("cli1")}), 1);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "--set", "slam.sigma_pixel=-1", "--out", outDir("cli2")}), 1);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "--set", "slam.sigma_pixel=nan", "--out", outDir("cli3")}), 1);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "--set", "bogus.key=1", "--out", outDir("cli4")}), 1);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "/nonexistent.rawlog", "--out", outDir("cli5")}), 1);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", "--calib", "/nonexistent/calib.txt", "--out", outDir("cli6")}), 1);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("sigma_pixle"), std::string::npos) << err;
  EXPECT_NE(err.find("did you mean 'sigma_pixel'"), std::string::npos) << err;
  EXPECT_NE(err.find("[slam] sigma_pixel"), std::string::npos) << err;
  EXPECT_NE(err.find("[bogus]"), std::string::npos) << err;
  EXPECT_NE(err.find("/nonexistent.rawlog"), std::string::npos) << err;
  EXPECT_NE(err.find("/nonexistent/calib.txt"), std::string::npos) << err;
}

TEST(AppCli, FieldOfViewGuessForAnInputWithoutCalibration)
{
  // A folder of images without calib.txt: refused with a message naming --fov; run with --fov 60 on a
  // pinhole of the images' own size, written to calib_guessed.txt; --fov with --calib is bad usage.
  const std::string folder = outDir("uncalibrated_input");
  std::filesystem::create_directories(folder + "/rgb");
  cv::Mat texture(340, 440, CV_8UC1);
  cv::RNG rng(5);
  rng.fill(texture, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 1.5);
  {
    std::ofstream list(folder + "/rgb.txt");
    for (int k = 0; k < 12; ++k)
    {
      const std::string name = "rgb/" + std::to_string(k) + ".png";
      cv::imwrite(folder + "/" + name, texture(cv::Rect(20 + k, 20, 400, 300)));
      list << k / 30.0 << " " << name << "\n";
    }
  }
  testing::internal::CaptureStderr();
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", folder, "--out", outDir("fov_none"), "--no-gui"}), 1);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("--fov"), std::string::npos) << err;

  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", folder, "--fov", "0"}), 2);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", folder, "--fov", "wide"}), 2);
  EXPECT_EQ(runApp({sourceDir() + "/ini/single.ini", folder, "--fov", "60", "--calib", folder + "/x.txt"}), 2);

  const std::string out = outDir("fov_60");
  app::TRunSummary s;
  ASSERT_EQ(runApp({sourceDir() + "/ini/single.ini", folder, "--fov", "60", "--out", out, "--no-gui"},
                   &s),
            0);
  EXPECT_EQ(s.framesProcessed, 12u);
  const auto cam = camera::loadCalibFile(out + "/calib_guessed.txt");
  EXPECT_EQ(cam->modelName(), "pinhole");
  EXPECT_EQ(cam->width(), 400);
  EXPECT_EQ(cam->height(), 300);
  EXPECT_NEAR(cam->fx(), 200 / std::tan(M_PI / 6), 1e-9);
  EXPECT_NEAR(cam->cx(), 199.5, 1e-12);
  EXPECT_NEAR(cam->cy(), 149.5, 1e-12);
}
