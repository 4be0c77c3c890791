/* Fuzz target: the rawlog reader (io::CRawlogSource) on arbitrary bytes. */
#include "fuzz_common.h"

#include <immslam/io/CRawlogSource.h>

#include <opencv2/core.hpp>

namespace immslam::fuzz
{
int fuzzRawlog(const std::uint8_t* data, std::size_t size)
{
  const std::string path = fuzzTempDir() + "/fuzz.rawlog";
  writeFile(path, std::string(reinterpret_cast<const char*>(data), size));
  std::unique_ptr<io::CRawlogSource> src;
  try
  {
    src = std::make_unique<io::CRawlogSource>(path);
  }
  catch (const std::exception& e)
  {
    requireMentions(e, path, "CRawlogSource");
    return 0;
  }
  (void)src->describe();
  (void)src->groundTruth();
  io::TFrame f;
  std::string why;
  std::size_t results = 0;
  for (; results < 100000; ++results)
  {
    const auto st = src->next(f, why);
    if (st == io::ENextStatus::End) break;
    if (st == io::ENextStatus::Frame && (f.grey.empty() || f.grey.type() != CV_8UC1))
      fail("CRawlogSource: a frame without an 8-bit grey image");
    if (st == io::ENextStatus::Skipped && why.empty()) fail("CRawlogSource: skipped without a reason");
  }
  // sizeHint() counts the next() results before End (the first pass and the stream agree).
  if (results != src->sizeHint())
    fail("CRawlogSource: " + std::to_string(results) + " results but sizeHint() " + std::to_string(src->sizeHint()));
  return 0;
}
}  // namespace immslam::fuzz
