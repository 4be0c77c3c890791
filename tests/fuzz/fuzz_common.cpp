/* imm-monoslam fuzz targets: the private temporary folder and small helpers. */
#include "fuzz_common.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <unistd.h>

namespace immslam::fuzz
{
namespace
{
/** Removes the folder at process exit. */
struct TTempDir
{
  std::string path;
  TTempDir()
  {
    const char* base = std::getenv("TMPDIR");
    path = std::string(base && *base ? base : "/tmp") + "/immslam-fuzz-" + std::to_string(::getpid());
    std::filesystem::create_directories(path);
  }
  ~TTempDir()
  {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};
}  // namespace

const std::string& fuzzTempDir()
{
  static const TTempDir dir;
  return dir.path;
}

void writeFile(const std::string& path, const std::string& bytes)
{
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

void fail(const std::string& what)
{
  std::fprintf(stderr, "\nimm-monoslam fuzz target: property violated: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

void requireMentions(const std::exception& e, const std::string& name, const std::string& target)
{
  const std::string m = e.what();
  if (m.find(name) == std::string::npos) fail(target + ": the error does not name '" + name + "': " + m);
}
}  // namespace immslam::fuzz
