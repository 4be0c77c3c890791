/* imm-monoslam fuzz targets: the list of targets (for the regression test). */
#include "fuzz_targets.h"

namespace immslam::fuzz
{
const std::vector<TFuzzTarget>& fuzzTargets()
{
  static const std::vector<TFuzzTarget> targets{
      {"calib", &fuzzCalib}, {"dataset", &fuzzDataset}, {"ini", &fuzzIni}, {"rawlog", &fuzzRawlog}};
  return targets;
}
}  // namespace immslam::fuzz
