/* Shared helpers of the robustness tests (issue 8): rendered inputs under the build tree, damaged
 * copies of them, in-process runs of the application with its error text, and checks that every
 * output file is well formed (no NaN, unit quaternions, probabilities summing to one). */
#pragma once

#include "../system/test_helpers.h"

#include <immslam/io/dataset2rawlog.h>
#include <immslam/sim/CSimulator.h>
#include <immslam/sim/TScenario.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace immslam::robust
{
namespace fs = std::filesystem;

/** A fresh, empty folder build/test-out/robustness/<name> (never under ../shared). */
inline std::string freshDir(const std::string& name)
{
  const fs::path d = fs::path(IMMSLAM_BINARY_DIR) / "test-out" / "robustness" / name;
  fs::remove_all(d);
  fs::create_directories(d);
  return d.string();
}

/** A fresh folder build/test-out/robustness/<name>_<pid> for data shared by the tests of one process
 * (ctest runs every TEST in its own process, in parallel); removed when the process exits. */
inline std::string processDir(const std::string& name)
{
  struct TDirs
  {
    std::vector<std::string> paths;
    ~TDirs()
    {
      for (const auto& p : paths)
      {
        std::error_code ec;
        fs::remove_all(p, ec);
      }
    }
  };
  static TDirs dirs;
  static std::mutex mtx;
  const std::string d = freshDir(name + "_" + std::to_string(::getpid()));
  std::lock_guard<std::mutex> lock(mtx);
  dirs.paths.push_back(d);
  return d;
}

/** Path of a file of the source tree. */
inline std::string src(const std::string& rel) { return std::string(IMMSLAM_SOURCE_DIR) + "/" + rel; }

/** What one in-process run of imm-monoslam gave. */
struct TAppRun
{
  int status = -1;
  std::string err;  ///< everything written to stderr
  std::string out;  ///< everything written to stdout (the summary line)
  app::TRunSummary summary;
};

/** Runs imm-monoslam in-process (quiet, no GUI), capturing stderr and stdout. */
inline TAppRun runApp(std::vector<std::string> args)
{
  args.push_back("--no-gui");
  TAppRun r;
  testing::internal::CaptureStderr();
  testing::internal::CaptureStdout();
  r.status = test::runApp(args, &r.summary);
  r.out = testing::internal::GetCapturedStdout();
  r.err = testing::internal::GetCapturedStderr();
  return r;
}

/** Renders the first n frames of a scenario file (ini/scenarios/...) as a dataset folder. */
inline void renderDataset(const std::string& scenario, const std::string& folder, std::size_t n,
                          const std::vector<std::string>& overrides = {})
{
  sim::CSimulator s(sim::TScenario::loadFile(scenario, overrides));
  s.writeDataset(folder, n);
}

/** A 40-frame handheld.ini dataset rendered once per process (read-only: copy before damaging). */
inline const std::string& baseDataset()
{
  static std::once_flag once;
  static std::string dir;
  std::call_once(once, [] {
    dir = processDir("base_handheld40");
    renderDataset(src("ini/scenarios/handheld.ini"), dir, 40);
  });
  return dir;
}

/** A copy of baseDataset() (rgb/, rgb.txt, calib.txt, groundtruth.txt) in a fresh folder. */
inline std::string copyBase(const std::string& name)
{
  const std::string d = freshDir(name);
  for (const auto& e : fs::directory_iterator(baseDataset()))
    fs::copy(e.path(), fs::path(d) / e.path().filename(), fs::copy_options::recursive);
  return d;
}

/** One entry of rgb.txt. */
struct TRgbLine
{
  std::string stamp, path;
};

inline std::vector<TRgbLine> readRgb(const std::string& folder)
{
  std::vector<TRgbLine> out;
  std::ifstream f(folder + "/rgb.txt");
  std::string line;
  while (std::getline(f, line))
  {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    TRgbLine l;
    is >> l.stamp >> l.path;
    out.push_back(l);
  }
  return out;
}

inline void writeRgb(const std::string& folder, const std::vector<TRgbLine>& lines)
{
  std::ofstream f(folder + "/rgb.txt");
  f << "# timestamp filename\n";
  for (const auto& l : lines) f << l.stamp << " " << l.path << "\n";
}

/** An embedded-image rawlog (plain observations, gzip) of a dataset folder. */
inline std::string makeRawlog(const std::string& folder, const std::string& rawlog,
                              io::ERawlogLayout layout = io::ERawlogLayout::Observations)
{
  io::TDataset2RawlogOptions o;
  o.embedImages = true;
  o.layout = layout;
  io::convertDatasetToRawlog(folder, rawlog, o);
  return rawlog;
}

/** Splits a line on `sep` (blank-separated when sep == ' '). */
inline std::vector<std::string> splitFields(const std::string& line, char sep)
{
  std::vector<std::string> out;
  if (sep == ' ')
  {
    std::istringstream is(line);
    for (std::string w; is >> w;) out.push_back(w);
    return out;
  }
  std::stringstream ss(line);
  for (std::string c; std::getline(ss, c, sep);) out.push_back(c);
  return out;
}

/** Parses a whole field as a finite number (false for NaN, inf, text). */
inline bool finiteNumber(const std::string& s, double& v)
{
  if (s.empty()) return false;
  char* end = nullptr;
  v = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && std::isfinite(v);
}

/** The per-frame outputs of a run, read back and checked. */
struct TOutputs
{
  std::vector<std::vector<double>> traj;   ///< trajectory.txt rows (8 numbers)
  std::vector<std::vector<double>> probs;  ///< model_probabilities.csv rows
  std::vector<std::vector<std::string>> stats;  ///< frame_stats.csv rows (header first)
  std::size_t mapRows = 0;                 ///< map.csv rows without the header (0 if absent)
  bool haveMap = false;
};

/** Reads the output folder of a run and checks every number (ADD_FAILURE on the first bad value of
 * each file): trajectory.txt has 8 finite numbers a line, unit quaternions and (monotonicTime)
 * non-decreasing timestamps; model_probabilities.csv rows are finite, in [0, 1] and sum to 1; frame_stats.csv and
 * map.csv hold no NaN/inf; the three per-frame files have one row per processed frame. */
inline TOutputs readAndCheckOutputs(const std::string& dir, bool requireMap = true, bool monotonicTime = true)
{
  TOutputs o;
  {
    std::ifstream f(dir + "/trajectory.txt");
    EXPECT_TRUE(f.good()) << dir << "/trajectory.txt missing";
    std::string line;
    for (int n = 1; std::getline(f, line); ++n)
    {
      const auto w = splitFields(line, ' ');
      std::vector<double> row;
      for (const auto& s : w)
      {
        double v = 0;
        if (!finiteNumber(s, v))
        {
          ADD_FAILURE() << dir << "/trajectory.txt:" << n << ": bad number '" << s << "'";
          return o;
        }
        row.push_back(v);
      }
      if (row.size() != 8)
      {
        ADD_FAILURE() << dir << "/trajectory.txt:" << n << ": " << row.size() << " fields";
        return o;
      }
      const double qn = std::sqrt(row[4] * row[4] + row[5] * row[5] + row[6] * row[6] + row[7] * row[7]);
      EXPECT_NEAR(qn, 1.0, 1e-9) << dir << "/trajectory.txt:" << n;
      o.traj.push_back(row);
    }
  }
  {
    const auto rows = test::readCsv(dir + "/model_probabilities.csv");
    EXPECT_FALSE(rows.empty()) << dir << "/model_probabilities.csv missing";
    for (std::size_t i = 1; i < rows.size(); ++i)
    {
      std::vector<double> row;
      double sum = 0;
      for (std::size_t j = 0; j < rows[i].size(); ++j)
      {
        double v = 0;
        if (!finiteNumber(rows[i][j], v))
        {
          ADD_FAILURE() << dir << "/model_probabilities.csv row " << i << ": bad number '" << rows[i][j] << "'";
          return o;
        }
        if (j > 0)
        {
          EXPECT_GE(v, 0.0);
          EXPECT_LE(v, 1.0);
          sum += v;
        }
        row.push_back(v);
      }
      EXPECT_NEAR(sum, 1.0, 1e-6) << dir << "/model_probabilities.csv row " << i;
      o.probs.push_back(row);
    }
  }
  o.stats = test::readCsv(dir + "/frame_stats.csv");
  EXPECT_FALSE(o.stats.empty()) << dir << "/frame_stats.csv missing";
  for (std::size_t i = 1; i < o.stats.size(); ++i)
    for (std::size_t j = 0; j < o.stats[i].size(); ++j)
    {
      const std::string& c = o.stats[i][j];
      double v = 0;
      const bool text = !c.empty() && (std::isalpha(static_cast<unsigned char>(c[0])) != 0) && c != "nan" &&
                        c != "inf" && c != "-nan";
      if (!text && !finiteNumber(c, v))
      {
        ADD_FAILURE() << dir << "/frame_stats.csv row " << i << " column " << o.stats[0][j] << ": '" << c << "'";
        break;
      }
    }
  if (fs::exists(dir + "/map.csv"))
  {
    o.haveMap = true;
    const auto rows = test::readCsv(dir + "/map.csv");
    o.mapRows = rows.empty() ? 0 : rows.size() - 1;
    for (std::size_t i = 1; i < rows.size(); ++i)
      for (std::size_t j = 1; j < 4 && j < rows[i].size(); ++j)
      {
        double v = 0;
        if (!finiteNumber(rows[i][j], v))
        {
          ADD_FAILURE() << dir << "/map.csv row " << i << ": '" << rows[i][j] << "'";
          break;
        }
      }
  }
  else if (requireMap)
  {
    ADD_FAILURE() << dir << "/map.csv missing";
  }
  EXPECT_EQ(o.probs.size(), o.traj.size()) << dir;
  EXPECT_EQ(o.stats.empty() ? 0 : o.stats.size() - 1, o.traj.size()) << dir;
  if (monotonicTime)
  {
    for (std::size_t i = 1; i < o.traj.size(); ++i)
    {
      EXPECT_GE(o.traj[i][0], o.traj[i - 1][0]) << dir << "/trajectory.txt:" << i + 1;
    }
  }
  return o;
}

/** The lines of a text file. */
inline std::vector<std::string> readLines(const std::string& path)
{
  std::vector<std::string> out;
  std::ifstream f(path);
  for (std::string l; std::getline(f, l);) out.push_back(l);
  return out;
}
}  // namespace immslam::robust
