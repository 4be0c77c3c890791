/* imm-monoslam — deterministic parallel-for over a persistent worker pool (dynamic scheduling). */
#include <immslam/math/parallel.h>

#include <algorithm>
#include <chrono>

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define IMMSLAM_CPU_RELAX() _mm_pause()
#else
#define IMMSLAM_CPU_RELAX() std::this_thread::yield()
#endif

namespace immslam::math
{
namespace
{
/** How long an idle thread polls before blocking: longer than the gap between the parallel
 * sections of one frame (tens of microseconds), much shorter than a frame. */
constexpr std::chrono::microseconds kSpin{100};

/** Polls cond() for up to kSpin; true if it became true. */
template <class Cond>
bool spinUntil(Cond&& cond)
{
  const auto t0 = std::chrono::steady_clock::now();
  for (;;)
  {
    for (int k = 0; k < 64; ++k)
    {
      if (cond()) return true;
      IMMSLAM_CPU_RELAX();
    }
    if (std::chrono::steady_clock::now() - t0 > kSpin) return cond();
  }
}

/** The ticket: (generation << 32) | (count << 16) | next index. The count of a job travels in the
 * same atomic word as its generation and next index, so a thread still looping over an earlier
 * job can never pair that job's ticket with the next job's count: before, a worker late in its
 * previous job read the new count beside the old ticket, claimed one index too many (run twice, on
 * two threads) and counted it done, and the caller's wait for done == count never ended (a hang
 * seen after ~10^5 jobs, with more threads than cores). */
constexpr int kIndexBits = 16;
constexpr std::uint64_t kIndexMask = (std::uint64_t(1) << kIndexBits) - 1;
constexpr int kMaxJobCount = static_cast<int>(kIndexMask);

std::uint64_t packTicket(std::uint32_t gen, int count)
{
  return (static_cast<std::uint64_t>(gen) << 32) | (static_cast<std::uint64_t>(count) << kIndexBits);
}
}  // namespace

CThreadPool::CThreadPool(unsigned nThreads)
{
  m_nThreads = nThreads ? nThreads : std::max(1u, std::thread::hardware_concurrency());
  for (unsigned i = 1; i < m_nThreads; ++i) m_workers.emplace_back([this] { workerLoop(); });
}

CThreadPool::~CThreadPool()
{
  {
    std::lock_guard<std::mutex> lk(m_mutex);
    m_stop = true;
  }
  m_cvStart.notify_all();
  for (auto& t : m_workers) t.join();
}

void CThreadPool::runIndices(std::uint32_t gen)
{
  for (;;)
  {
    std::uint64_t t = m_ticket.load(std::memory_order_acquire);
    int k, count;
    do
    {
      if (static_cast<std::uint32_t>(t >> 32) != gen) return;  // a later job: not ours
      k = static_cast<int>(t & kIndexMask);
      count = static_cast<int>((t >> kIndexBits) & kIndexMask);
      if (k >= count) return;
    } while (!m_ticket.compare_exchange_weak(t, t + 1, std::memory_order_acq_rel, std::memory_order_acquire));
    // Index k of generation gen is ours: the job cannot change before it is counted done.
    try
    {
      (*m_job)(m_begin + k);
    }
    catch (...)
    {
      std::lock_guard<std::mutex> lk(m_mutex);
      if (!m_error) m_error = std::current_exception();
    }
    if (m_done.fetch_add(1, std::memory_order_acq_rel) + 1 == count)
    {
      std::lock_guard<std::mutex> lk(m_mutex);  // the caller may be about to sleep
      m_cvDone.notify_one();
    }
  }
}

void CThreadPool::workerLoop()
{
  std::uint32_t seen = static_cast<std::uint32_t>(m_ticket.load() >> 32);
  auto newJob = [&] {
    return m_stop.load(std::memory_order_acquire) ||
           static_cast<std::uint32_t>(m_ticket.load(std::memory_order_acquire) >> 32) != seen;
  };
  for (;;)
  {
    if (!spinUntil(newJob))
    {
      std::unique_lock<std::mutex> lk(m_mutex);
      m_cvStart.wait(lk, newJob);
    }
    if (m_stop.load()) return;
    seen = static_cast<std::uint32_t>(m_ticket.load(std::memory_order_acquire) >> 32);
    runIndices(seen);
  }
}

void CThreadPool::parallelFor(int begin, int end, const std::function<void(int)>& f)
{
  if (end <= begin) return;
  if (m_nThreads == 1 || end - begin == 1)
  {
    for (int i = begin; i < end; ++i) f(i);
    return;
  }
  if (end - begin > kMaxJobCount)
  {
    for (int b = begin; b < end; b += kMaxJobCount) parallelFor(b, std::min(end, b + kMaxJobCount), f);
    return;
  }
  const int count = end - begin;
  m_job = &f;
  m_begin = begin;
  m_error = nullptr;
  m_done.store(0, std::memory_order_relaxed);
  // Publishing the new generation (release) makes the job visible to whoever claims an index.
  const auto gen = static_cast<std::uint32_t>((m_ticket.load(std::memory_order_relaxed) >> 32) + 1);
  m_ticket.store(packTicket(gen, count), std::memory_order_release);
  {
    std::lock_guard<std::mutex> lk(m_mutex);  // no lost wake-up for a worker about to sleep
  }
  m_cvStart.notify_all();
  runIndices(gen);
  auto allDone = [&] { return m_done.load(std::memory_order_acquire) == count; };
  if (!spinUntil(allDone))
  {
    std::unique_lock<std::mutex> lk(m_mutex);
    m_cvDone.wait(lk, allDone);
  }
  std::exception_ptr err;
  {
    std::lock_guard<std::mutex> lk(m_mutex);
    err = m_error;
    m_error = nullptr;
  }
  m_job = nullptr;
  if (err) std::rethrow_exception(err);
}
}  // namespace immslam::math
