/* The command line of CONTRACT.md: usage errors, config errors naming the key, --help/--version. */
#include "test_helpers.h"

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
