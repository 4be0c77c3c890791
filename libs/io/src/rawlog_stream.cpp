/* imm-monoslam — rawlog object reader that reports truncation and corruption. */
#include "rawlog_stream.h"

#include "image_convert.h"

#include <mrpt/io/CFileGZInputStream.h>
#include <mrpt/io/CStream.h>
#include <opencv2/imgcodecs.hpp>

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
    if (!checkJpegImage(buffer, count)) return 0;
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
  /** MRPT's CImage deserializer hands the JPEG payload of a colour image to libjpeg with libjpeg's
   * default error handler, which calls exit() on a fatal error (a bad marker, not a JPEG at all):
   * one damaged frame would end the process with nothing written (found by fuzzing,
   * tests/fuzz/regressions/rawlog/image_jpeg_*). The stream follows the reads of a CImage as
   * MRPT 2.5 makes them (class name; version; v >= 6: external flag; colour flag; v >= 7: width,
   * height; then the payload size and the payload, for v >= 2 only for a colour image of positive
   * size) and decodes the payload first with OpenCV, whose libjpeg error handler returns instead of
   * exiting. A payload that is not a JPEG OpenCV can decode is refused as damage, before MRPT sees
   * it. Any read of an unexpected size drops the tracking (other data, not a CImage). */
  bool checkJpegImage(const void* buffer, size_t count)
  {
    const auto* b = static_cast<const unsigned char*>(buffer);
    const auto i32 = [&] {
      return static_cast<int32_t>(uint32_t(b[0]) | (uint32_t(b[1]) << 8) | (uint32_t(b[2]) << 16) | (uint32_t(b[3]) << 24));
    };
    const EImageRead st = m_img;
    m_img = EImageRead::None;
    switch (st)
    {
      case EImageRead::None: break;
      case EImageRead::Version:
        if (count != 1) break;
        m_imgVersion = b[0];
        if (m_imgVersion == 1)
          m_img = EImageRead::PayloadSize;
        else if (m_imgVersion >= 2 && m_imgVersion <= 9)
          m_img = m_imgVersion >= 6 ? EImageRead::External : EImageRead::HasColor;
        return true;
      case EImageRead::External:
        if (count == 1 && b[0] == 0) m_img = EImageRead::HasColor;
        return true;
      case EImageRead::HasColor:
        if (count == 1 && b[0] != 0) m_img = m_imgVersion >= 7 ? EImageRead::Width : EImageRead::PayloadSize;
        return true;
      case EImageRead::Width:
        if (count != 4) break;
        m_imgWidth = i32();
        m_img = EImageRead::Height;
        return true;
      case EImageRead::Height:
        if (count == 4 && m_imgWidth >= 1 && i32() >= 1) m_img = EImageRead::PayloadSize;
        return true;
      case EImageRead::PayloadSize:
        if (count != 4) break;
        m_jpegBytes = static_cast<uint32_t>(i32());
        if (m_jpegBytes < 4)  // MRPT would decode it (even 0 bytes) as a JPEG
        {
          m_implausible = "corrupt image: a JPEG of " + std::to_string(m_jpegBytes) + " bytes at byte " +
                          std::to_string(m_bytes - 4);
          return false;
        }
        m_img = EImageRead::Payload;
        return true;
      case EImageRead::Payload:
        if (count != m_jpegBytes) break;
        {
          const bool signature = b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF;
          cv::Mat decoded;
          if (signature)
          {
            const cv::Mat raw(1, static_cast<int>(std::min<size_t>(count, INT32_MAX)), CV_8UC1, const_cast<unsigned char*>(b));
            try
            {
              decoded = cv::imdecode(raw, cv::IMREAD_REDUCED_GRAYSCALE_8);
            }
            catch (const cv::Exception&)
            {
              decoded.release();
            }
          }
          if (decoded.empty())
          {
            m_implausible = std::string("corrupt image: ") + (signature ? "undecodable" : "not a") + " JPEG of " +
                            std::to_string(count) + " bytes at byte " + std::to_string(m_bytes - count);
            return false;
          }
        }
        return true;
    }
    // A class name (see checkContainerCount()): a CImage begins.
    const std::size_t len = count > 127 ? 0 : static_cast<std::size_t>(std::find(b, b + count, 0) - b);
    static const std::string kImage = "CImage";
    if (len >= kImage.size() &&
        std::equal(kImage.begin(), kImage.end(), b + len - kImage.size(), [](char x, unsigned char y) {
          return std::tolower(static_cast<unsigned char>(x)) == std::tolower(y);
        }))
      m_img = EImageRead::Version;
    return true;
  }

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

  enum class EImageRead
  {
    None,
    Version,
    External,
    HasColor,
    Width,
    Height,
    PayloadSize,
    Payload
  };
  EImageRead m_img = EImageRead::None;  ///< where the reads of a CImage are (checkJpegImage())
  int m_imgVersion = 0;
  int32_t m_imgWidth = 0;
  uint32_t m_jpegBytes = 0;
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
    if (err.size() > 400) err.replace(400, std::string::npos, "...");
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
