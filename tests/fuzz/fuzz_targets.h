/* imm-monoslam fuzz targets (issue 8): one function per parser, called by libFuzzer through
 * fuzz_entry.cpp (clang, -DIMMSLAM_BUILD_FUZZERS=ON) and by fuzz_regression_unittest on the
 * committed seeds and crash inputs (any compiler). Each returns 0 and must never crash, leak,
 * hang or trip a sanitizer on any input; malformed input may only end in a std::exception. */
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace immslam::fuzz
{
/** calib.txt: camera::parseCalibLine on every line and camera::loadCalibFile on the whole input
 * (as a file); a parsed model must print and re-parse to the same parameters. */
int fuzzCalib(const std::uint8_t* data, std::size_t size);

/** A dataset folder: the input split at lines "%%" into rgb.txt, groundtruth.txt and calib.txt;
 * io::parseRgbTxt, core::readTumTrajectory, and io::CDatasetFolderSource drained on a temporary
 * folder (its rgb/ holds one valid 8x6 PNG, a.png, that entries may name). */
int fuzzDataset(const std::uint8_t* data, std::size_t size);

/** An ini file: core::checkIniSyntax, the strict core readers on every key, core::checkKnownKeys
 * and the loadFromConfigFile() (and validation) of every options class of the system ([system],
 * [slam], [imm], [ransac], [shadow]), camera::loadCameraFromConfig ([camera]) and
 * sim::TScenario::fromConfig, through mrpt::config::CConfigFileMemory. */
int fuzzIni(const std::uint8_t* data, std::size_t size);

/** An MRPT rawlog: the bytes written to a temporary file, opened with io::CRawlogSource and
 * drained (next() until End). */
int fuzzRawlog(const std::uint8_t* data, std::size_t size);

/** A target by name. */
struct TFuzzTarget
{
  const char* name;  ///< "calib", "dataset", "ini", "rawlog": also the corpus folder names
  int (*run)(const std::uint8_t*, std::size_t);
};

/** Every target. */
const std::vector<TFuzzTarget>& fuzzTargets();

/** A private temporary folder of this process (created on first use). */
const std::string& fuzzTempDir();
}  // namespace immslam::fuzz
