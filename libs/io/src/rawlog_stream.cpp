/* imm-monoslam — rawlog object reader that reports truncation and corruption. */
#include "rawlog_stream.h"

#include "image_convert.h"

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CStream.h>

#include <array>
#include <fstream>
#include <new>
#include <stdexcept>

namespace immslam::io::detail
{
TGzipInfo inspectGzip(const std::string& path)
{
  TGzipInfo g;
  std::ifstream f(path, std::ios::binary);
  if (!f) return g;
  std::array<unsigned char, 2> magic{};
  if (!f.read(reinterpret_cast<char*>(magic.data()), 2)) return g;
  g.isGzip = magic[0] == 0x1f && magic[1] == 0x8b;
  f.seekg(0, std::ios::end);
  const auto size = static_cast<long long>(f.tellg());
  g.hasTrailer = g.isGzip && size >= 18;  // 10-byte header + 8-byte trailer
  if (!g.hasTrailer) return g;
  std::array<unsigned char, 4> t{};
  f.seekg(size - 4);
  if (!f.read(reinterpret_cast<char*>(t.data()), 4))
  {
    g.hasTrailer = false;
    return g;
  }
  g.isize = uint32_t(t[0]) | (uint32_t(t[1]) << 8) | (uint32_t(t[2]) << 16) | (uint32_t(t[3]) << 24);
  return g;
}

/** Forwards reads to a CFileGZInputStream, counts the uncompressed bytes and makes every read
 * all-or-nothing: gzread returns less than asked only at the end of the data (or -1 on a gzip
 * error), and a partial value must never reach a deserializer (a half-read size field could ask
 * for gigabytes), so a short read returns 0 and CArchive throws at once. */
class CCountingGzStream : public mrpt::io::CStream
{
 public:
  explicit CCountingGzStream(const std::string& path) : m_path(path)
  {
    std::string err;
    if (!m_gz.open(path, err))
      throw std::runtime_error("cannot open rawlog " + path + (err.empty() ? "" : ": " + err));
  }

  size_t Read(void* buffer, size_t count) override
  {
    if (m_eof || m_gzError || count == 0) return 0;
    const size_t got = m_gz.Read(buffer, count);
    if (got > count)  // gzread returned -1
    {
      m_gzError = true;
      return 0;
    }
    m_bytes += got;
    if (got < count)
    {
      m_eof = true;
      return 0;
    }
    return got;
  }
  size_t Write(const void*, size_t) override
  {
    throw std::runtime_error("rawlog " + m_path + " is opened for reading");
  }
  uint64_t Seek(int64_t, CStream::TSeekOrigin) override
  {
    throw std::runtime_error("rawlog " + m_path + ": seeking is not supported");
  }
  uint64_t getTotalBytesCount() const override { return m_gz.getTotalBytesCount(); }
  uint64_t getPosition() const override { return m_bytes; }
  std::string getStreamDescription() const override { return "rawlog " + m_path; }

  uint64_t bytes() const { return m_bytes; }
  bool eof() const { return m_eof; }
  bool gzError() const { return m_gzError; }

 private:
  std::string m_path;
  mrpt::io::CFileGZInputStream m_gz;
  uint64_t m_bytes = 0;
  bool m_eof = false;
  bool m_gzError = false;
};

CRawlogReader::CRawlogReader(const std::string& path, const TGzipInfo& gz)
    : m_stream(std::make_unique<CCountingGzStream>(path)), m_gz(gz)
{
  m_arch = mrpt::serialization::archiveUniquePtrFrom<mrpt::io::CStream>(*m_stream);
}

CRawlogReader::~CRawlogReader() = default;

CRawlogReader::EResult CRawlogReader::read(mrpt::serialization::CSerializable::Ptr& obj, std::string& why)
{
  obj.reset();
  if (m_state != EResult::Object)
  {
    why = m_why;
    return m_state;
  }
  const uint64_t before = m_stream->bytes();
  std::string err;
  try
  {
    obj = m_arch->ReadObject();
    if (obj)
    {
      ++m_entries;
      return EResult::Object;
    }
    err = "null object";
  }
  catch (const std::bad_alloc&)
  {
    err = "out of memory while reading an object (corrupt size field?)";
  }
  catch (const std::exception& e)
  {
    err = mrptMessage(e.what());
    if (err.size() > 400) err = err.substr(0, 400) + "...";
  }
  if (m_stream->gzError())
    m_why = "gzip data error (corrupt compressed data or CRC mismatch): " + err;
  else if (m_stream->bytes() == before && m_stream->eof() && err != "null object")
  {
    const bool sizeOk = !m_gz.hasTrailer || uint32_t(m_stream->bytes()) == m_gz.isize;
    if (sizeOk)
    {
      m_state = EResult::End;
      m_why.clear();
      why.clear();
      return m_state;
    }
    m_why = "data ends after " + std::to_string(m_stream->bytes()) +
            " uncompressed bytes but the gzip trailer says " + std::to_string(m_gz.isize) +
            " (file truncated)";
  }
  else if (m_stream->eof())
    m_why = "unexpected end of data (file truncated) in the next object: " + err;
  else
    m_why = "cannot parse the next object: " + err;
  m_state = EResult::Damage;
  why = m_why;
  return m_state;
}
}  // namespace immslam::io::detail
