/* Fuzz harness only: a replacement of the global operator new (a replaceable function, [new.delete])
 * that throws std::bad_alloc for any single allocation above 256 MiB.
 *
 * Why: MRPT's deserializers allocate whatever a length field says before reading the data (e.g.
 * operator>>(CArchive&, std::string&) resizes to a 32-bit length: up to 4 GiB, zero-filled). On a
 * corrupt rawlog that is a transient allocation which io::CRawlogReader survives (the read then
 * fails and the damage is reported; std::bad_alloc is caught as "corrupt size field?"), but under
 * AddressSanitizer it is reported as out-of-memory and it makes each such input take seconds. With
 * this cap those inputs take the bad_alloc path, which the reader must handle anyway, and the
 * fuzzer stays fast. Real runs are not capped: see doc/reliability.md. (Under ASan this also turns
 * off its new/delete mismatch check: every form below allocates with malloc and frees with free.) */
#include <cstddef>
#include <cstdlib>
#include <new>

namespace
{
constexpr std::size_t kMaxAllocation = std::size_t(256) << 20;

void* allocate(std::size_t size, std::size_t align)
{
  if (size > kMaxAllocation) throw std::bad_alloc();
  if (size == 0) size = 1;
  void* p = nullptr;
  if (align <= alignof(std::max_align_t))
    p = std::malloc(size);
  else if (posix_memalign(&p, align, size) != 0)
    p = nullptr;
  if (!p) throw std::bad_alloc();
  return p;
}
}  // namespace

// Every replaceable form (so that new and delete always pair malloc with free, also under ASan,
// whose own forms would otherwise be mixed with these).
void* operator new(std::size_t size) { return allocate(size, 0); }
void* operator new[](std::size_t size) { return allocate(size, 0); }
void* operator new(std::size_t size, std::align_val_t a) { return allocate(size, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t size, std::align_val_t a) { return allocate(size, static_cast<std::size_t>(a)); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept
{
  try
  {
    return allocate(size, 0);
  }
  catch (...)
  {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t& t) noexcept { return operator new(size, t); }
void* operator new(std::size_t size, std::align_val_t a, const std::nothrow_t&) noexcept
{
  try
  {
    return allocate(size, static_cast<std::size_t>(a));
  }
  catch (...)
  {
    return nullptr;
  }
}
void* operator new[](std::size_t size, std::align_val_t a, const std::nothrow_t& t) noexcept
{
  return operator new(size, a, t);
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
