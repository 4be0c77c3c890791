/* imm-monoslam — test helper of the io tests: a fresh temporary folder, removed at the end. */
#pragma once

#include <filesystem>
#include <string>
#include <unistd.h>

namespace immslam::io::test
{
/** A fresh temporary folder under the system's temp dir, unique per process and instance, removed
 * (with its content) when the object goes. \p tag names the test program in the folder name. */
class TempDir
{
 public:
  explicit TempDir(const std::string& tag)
  {
    static int counter = 0;
    m_path = std::filesystem::temp_directory_path() /
             ("immslam_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(m_path);
    std::filesystem::create_directories(m_path);
  }
  ~TempDir()
  {
    std::error_code ec;
    std::filesystem::remove_all(m_path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string str() const { return m_path.string(); }
  std::string operator/(const std::string& s) const { return (m_path / s).string(); }

 private:
  std::filesystem::path m_path;
};
}  // namespace immslam::io::test
