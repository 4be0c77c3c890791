/* Shared helpers of the system tests: run the application class in-process and read its outputs. */
#pragma once

#include <immslam/app/CImmMonoSlamApp.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace immslam::test
{
inline std::string sourceDir() { return IMMSLAM_SOURCE_DIR; }
inline std::string sharedData(const std::string& name) { return std::string(IMMSLAM_SHARED_DATA_DIR) + "/" + name; }
inline bool haveSharedData(const std::string& name) { return std::filesystem::exists(sharedData(name)); }

/** A fresh output folder under the build tree. */
inline std::string outDir(const std::string& name)
{
  const auto d = std::filesystem::path(IMMSLAM_BINARY_DIR) / "test-out" / name;
  std::filesystem::remove_all(d);
  return d.string();
}

/** Runs imm-monoslam in-process with these arguments; returns the exit status. */
inline int runApp(const std::vector<std::string>& args, app::TRunSummary* summary = nullptr)
{
  app::CImmMonoSlamApp app;
  app.setMinLoggingLevel(mrpt::system::LVL_WARN);
  std::vector<std::string> a = args;
  a.push_back("--quiet");
  const int st = app.initialize(a);
  if (st >= 0) return st;
  const int r = app.run();
  if (summary) *summary = app.summary();
  return r;
}

inline std::vector<std::vector<std::string>> readCsv(const std::string& path)
{
  std::vector<std::vector<std::string>> rows;
  std::ifstream f(path);
  std::string line;
  while (std::getline(f, line))
  {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string c;
    while (std::getline(ss, c, ',')) cells.push_back(c);
    rows.push_back(cells);
  }
  return rows;
}

inline std::string readFile(const std::string& path)
{
  std::ifstream f(path);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}
}  // namespace immslam::test
