/* imm-monoslam — rawlog object reader that reports truncation and corruption. */
#include "rawlog_stream.h"

#include "image_convert.h"

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CStream.h>

#include <algorithm>
#include <array>
#include <cctype>
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
    if (m_eof || m_gzError || !m_implausible.empty() || count == 0) return 0;
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
    if (!checkContainerCount(buffer, count)) return 0;
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
  /** Non-empty when an element count was refused (see checkContainerCount()). */
  const std::string& implausible() const { return m_implausible; }
  /** Gzip data: the bytes left are unknown (no bound but kMaxElements on counts). */
  void setIsGzip(bool g) { m_isGzip = g; }

 private:
  /** MRPT's deserializers of the container classes read an element count and resize to it before
   * reading any element: CActionCollection and CSensoryFrame resize a std::deque, which allocates
   * piece by piece, so a corrupt count in a 300-byte file makes MRPT allocate gigabytes (no single
   * allocation is large enough to fail; found by fuzzing, tests/fuzz/regressions/rawlog/). The
   * stream sees the class name (one read), then the container's own fields up to the first
   * element's class name: every 4-byte field there is a count (the other fields are 1-byte flags
   * and 8-byte times or poses, depending on the version). A count larger than the bytes left in
   * the data (each element takes at least one) or than kMaxElements is refused, and the read fails
   * as damage. Returns false when refused. */
  bool checkContainerCount(const void* buffer, size_t count)
  {
    static constexpr uint32_t kMaxElements = 1u << 20;
    const auto* b = static_cast<const unsigned char*>(buffer);
    if (count > 8) m_inContainerHeader = false;  // a class name: the container's elements begin
    if (m_inContainerHeader && count == 4)
    {
      const uint32_t n = uint32_t(b[0]) | (uint32_t(b[1]) << 8) | (uint32_t(b[2]) << 16) | (uint32_t(b[3]) << 24);
      const uint64_t total = m_gz.getTotalBytesCount();  // compressed size for gzip: no bound then
      const bool plainLeft = !m_isGzip && total >= m_bytes;
      if (n > kMaxElements || (plainLeft && n > total - m_bytes))
      {
        m_implausible = "implausible element count " + std::to_string(n) + " in a " + m_container + " at byte " +
                        std::to_string(m_bytes - 4) + " (corrupt size field)";
        return false;
      }
    }
    // A class name as MRPT resolves it: up to the first NUL, case-insensitive, with or without (or
    // with a garbled) namespace.
    const std::size_t len = count > 127 ? 0 : static_cast<std::size_t>(std::find(b, b + count, 0) - b);
    for (const std::string name : {"CActionCollection", "CSensoryFrame"})
      if (len >= name.size() &&
          std::equal(name.begin(), name.end(), b + len - name.size(), [](char x, unsigned char y) {
            return std::tolower(static_cast<unsigned char>(x)) == std::tolower(y);
          }))
      {
        m_inContainerHeader = true;
        m_container = name;
      }
    return true;
  }

  bool m_inContainerHeader = false;
  std::string m_container;
  std::string m_implausible;
  bool m_isGzip = false;

  std::string m_path;
  mrpt::io::CFileGZInputStream m_gz;
  uint64_t m_bytes = 0;
  bool m_eof = false;
  bool m_gzError = false;
};

CRawlogReader::CRawlogReader(const std::string& path, const TGzipInfo& gz)
    : m_stream(std::make_unique<CCountingGzStream>(path)), m_gz(gz)
{
  m_stream->setIsGzip(gz.isGzip);
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
  if (!m_stream->implausible().empty())
    m_why = m_stream->implausible();
  else if (m_stream->gzError())
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
