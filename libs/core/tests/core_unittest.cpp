/* Tests: strict config reading and unknown-key detection. */
#include <gtest/gtest.h>
#include <immslam/core/config.h>
#include <mrpt/config/CConfigFileMemory.h>

using namespace immslam;

namespace
{
struct TDemoOptions : public mrpt::config::CLoadableOptions
{
  double sigma_pixel = 1.0;
  int max_features = 10;
  bool enabled = true;
  std::vector<double> weights{1, 2};
  void loadFromConfigFile(const mrpt::config::CConfigFileBase& c, const std::string& s) override
  {
    IMMSLAM_LOAD_DOUBLE(sigma_pixel);
    IMMSLAM_LOAD_INT(max_features);
    IMMSLAM_LOAD_BOOL(enabled);
    IMMSLAM_LOAD_VECTOR(weights);
  }
  void saveToConfigFile(mrpt::config::CConfigFileBase& c, const std::string& s) const override
  {
    MRPT_SAVE_CONFIG_VAR_COMMENT(sigma_pixel, "px");
    MRPT_SAVE_CONFIG_VAR_COMMENT(max_features, "");
    MRPT_SAVE_CONFIG_VAR_COMMENT(enabled, "");
    c.write(s, "weights", std::string("[1 2]"));
  }
};

std::string errorOf(const std::function<void()>& f)
{
  try
  {
    f();
  }
  catch (const std::exception& e)
  {
    return e.what();
  }
  return {};
}
}  // namespace

TEST(Config, StrictReadsAndDefaults)
{
  mrpt::config::CConfigFileMemory c("[slam]\nsigma_pixel = 0.5\nmax_features = 7\nenabled = false\nweights = [3, 4 5]\n");
  TDemoOptions o;
  o.loadFromConfigFile(c, "slam");
  EXPECT_EQ(o.sigma_pixel, 0.5);
  EXPECT_EQ(o.max_features, 7);
  EXPECT_FALSE(o.enabled);
  EXPECT_EQ(o.weights, (std::vector<double>{3, 4, 5}));
  TDemoOptions d;
  d.loadFromConfigFile(mrpt::config::CConfigFileMemory(""), "slam");
  EXPECT_EQ(d.sigma_pixel, 1.0);
}

TEST(Config, BadValuesNameSectionAndKey)
{
  TDemoOptions o;
  auto err = errorOf([&] { o.loadFromConfigFile(mrpt::config::CConfigFileMemory("[slam]\nsigma_pixel = abc\n"), "slam"); });
  EXPECT_NE(err.find("[slam] sigma_pixel = 'abc'"), std::string::npos) << err;
  err = errorOf([&] { o.loadFromConfigFile(mrpt::config::CConfigFileMemory("[slam]\nsigma_pixel = nan\n"), "slam"); });
  EXPECT_NE(err.find("NaN"), std::string::npos) << err;
  err = errorOf([&] { o.loadFromConfigFile(mrpt::config::CConfigFileMemory("[slam]\nmax_features = 2.5\n"), "slam"); });
  EXPECT_NE(err.find("not an integer"), std::string::npos) << err;
  err = errorOf([&] { o.loadFromConfigFile(mrpt::config::CConfigFileMemory("[slam]\nenabled = maybe\n"), "slam"); });
  EXPECT_NE(err.find("enabled"), std::string::npos) << err;
  err = errorOf([&] { core::requirePositive(-1, "slam", "sigma_pixel"); });
  EXPECT_NE(err.find("[slam] sigma_pixel"), std::string::npos) << err;
}

TEST(Config, UnknownKeysAreNamedWithAHint)
{
  TDemoOptions o;
  const auto known = core::knownKeys(o, "slam");
  EXPECT_EQ(known.size(), 4u);
  mrpt::config::CConfigFileMemory c("[slam]\nsigma_pixle = 1\nfoo = 2\nmax_features = 3\n");
  const auto err = errorOf([&] { core::checkKnownKeys(c, "slam", known); });
  EXPECT_NE(err.find("sigma_pixle"), std::string::npos) << err;
  EXPECT_NE(err.find("did you mean 'sigma_pixel'"), std::string::npos) << err;
  EXPECT_NE(err.find("foo"), std::string::npos) << err;
  EXPECT_EQ(err.find("max_features"), std::string::npos) << err;
  EXPECT_NO_THROW(core::checkKnownKeys(c, "absent", known));
}
