/* Tests: strict config reading and unknown-key detection. */
#include <gtest/gtest.h>
#include <immslam/core/config.h>
#include <mrpt/config/CConfigFileMemory.h>

#include <clocale>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

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

TEST(Config, NumbersAreDecimalWhateverTheLocale)
{
  TDemoOptions o;
  o.loadFromConfigFile(mrpt::config::CConfigFileMemory("[slam]\nsigma_pixel = +2.5e-1\n"), "slam");
  EXPECT_EQ(o.sigma_pixel, 0.25);
  for (const char* v : {"0x10", "1.5.2", "--1", "+-1", "1e400", "2,5", ""})
  {
    const auto err = errorOf([&] {
      o.loadFromConfigFile(mrpt::config::CConfigFileMemory(std::string("[slam]\nsigma_pixel = ") + v + "x\n"), "slam");
    });
    EXPECT_NE(err.find("[slam] sigma_pixel"), std::string::npos) << v << ": " << err;
  }
  EXPECT_NE(errorOf([&] { o.loadFromConfigFile(mrpt::config::CConfigFileMemory("[slam]\nsigma_pixel = 1e400\n"), "slam"); })
                .find("out of the range"),
            std::string::npos);
  // A decimal-comma locale must not change how "0.5" reads (std::stod would stop at the '.').
  const std::string old = std::setlocale(LC_NUMERIC, nullptr);
  if (std::setlocale(LC_NUMERIC, "de_DE.UTF-8") || std::setlocale(LC_NUMERIC, "fr_FR.UTF-8"))
  {
    o.loadFromConfigFile(mrpt::config::CConfigFileMemory("[slam]\nsigma_pixel = 0.5\n"), "slam");
    EXPECT_EQ(o.sigma_pixel, 0.5);
    std::setlocale(LC_NUMERIC, old.c_str());
  }
}

TEST(Config, IniSyntaxErrorsNameTheLine)
{
  EXPECT_NO_THROW(core::checkIniSyntax("# c\n; c\n// c\n@define X 1\n\n[a]  # c\nk = v = w\n k2=  \n[b]\nk = 1\n", "f.ini"));
  const std::vector<std::pair<std::string, std::string>> bad{
      {"[slam]\nsigma_pixel 2\n", "f.ini:2: 'sigma_pixel 2' is not 'key = value'"},
      {"sigma_pixel = 2\n[slam]\n", "f.ini:1: key 'sigma_pixel' outside any [section]"},
      {"[slam]\n= 2\n", "f.ini:2: '= 2': no key"},
      {"[slam\nk = 1\n", "f.ini:1: malformed section header"},
      {"[]\n", "f.ini:1: malformed section header"},
      {"[a] b\n", "f.ini:1: malformed section header"},
      {"[slam]\nk = 1\n\nk = 2\n", "f.ini:4: [slam] k given twice (also on line 2)"},
      {"[slam]\nmy key = 1\n", "f.ini:2: malformed key 'my key'"},
      {"[slam]\n\x01\xff\n", "f.ini:2: '?" "?' is not"},
  };
  for (const auto& [text, what] : bad)
  {
    const auto err = errorOf([&] { core::checkIniSyntax(text, "f.ini"); });
    EXPECT_NE(err.find(what), std::string::npos) << "'" << text << "' gave: " << err;
  }
  // The same key in two sections is fine.
  EXPECT_NO_THROW(core::checkIniSyntax("[a]\nk = 1\n[b]\nk = 1\n", "f.ini"));
}

TEST(Config, ShippedConfigsHaveCleanSyntax)
{
  namespace fs = std::filesystem;
  int n = 0;
  for (const auto* dir : {"/ini", "/ini/scenarios"})
    for (const auto& e : fs::directory_iterator(std::string(IMMSLAM_SOURCE_DIR) + dir))
      if (e.path().extension() == ".ini")
      {
        std::ifstream f(e.path());
        std::stringstream ss;
        ss << f.rdbuf();
        EXPECT_NO_THROW(core::checkIniSyntax(ss.str(), e.path().string())) << e.path();
        ++n;
      }
  EXPECT_GE(n, 2);
}
