/* imm-monoslam — private: reading rawlog objects one by one, telling a clean end of file from damage. */
#pragma once

#include <mrpt/serialization/CArchive.h>
#include <mrpt/serialization/CSerializable.h>

#include <cstdint>
#include <memory>
#include <string>

namespace immslam::io::detail
{
/** What the file's gzip framing says (read directly from its first and last bytes). */
struct TGzipInfo
{
  bool isGzip = false;      ///< starts with the gzip magic 1f 8b (else read as plain data)
  bool hasTrailer = false;  ///< long enough to hold the 8-byte trailer
  uint32_t isize = 0;       ///< trailer ISIZE: uncompressed size mod 2^32 (valid if the file is complete)
};

/** Inspects the gzip header and trailer of a file (zeros/false if unreadable). */
TGzipInfo inspectGzip(const std::string& path);

class CCountingGzStream;

/** Reads top-level objects of a rawlog through mrpt::io::CFileGZInputStream and a byte-counting
 * stream adapter. Unlike CRawlog::getActionObservationPairOrObservation (which prints to cerr and
 * returns false for both), it tells apart:
 * - a clean end: no byte of a new object was available and the uncompressed size matches the gzip
 *   trailer;
 * - damage: an object started but could not be completed (truncated data, corrupt object, gzip data
 *   or CRC error), or the data stopped between two objects while the gzip trailer says more was
 *   written. */
class CRawlogReader
{
 public:
  enum class EResult
  {
    Object,  ///< obj holds the next top-level object
    End,     ///< clean end of file
    Damage   ///< `why` says what is wrong; the reader stays in this state
  };

  /** \throws std::runtime_error naming the file if it cannot be opened. */
  CRawlogReader(const std::string& path, const TGzipInfo& gz);
  ~CRawlogReader();
  CRawlogReader(const CRawlogReader&) = delete;
  CRawlogReader& operator=(const CRawlogReader&) = delete;

  /** Reads the next top-level object. */
  EResult read(mrpt::serialization::CSerializable::Ptr& obj, std::string& why);

  /** Number of complete top-level objects read so far. */
  std::size_t entries() const { return m_entries; }

 private:
  std::unique_ptr<CCountingGzStream> m_stream;
  mrpt::serialization::CArchive::UniquePtr m_arch;
  TGzipInfo m_gz;
  std::size_t m_entries = 0;
  EResult m_state = EResult::Object;
  std::string m_why;
};
}  // namespace immslam::io::detail
