/* libFuzzer entry point of one target: IMMSLAM_FUZZ_FN is set per executable by CMakeLists.txt. */
#include "fuzz_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  return IMMSLAM_FUZZ_FN(data, size);
}
