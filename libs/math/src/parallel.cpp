/* imm-monoslam — deterministic parallel-for over a persistent worker pool. */
#include <immslam/math/parallel.h>

#include <algorithm>

namespace immslam::math
{
namespace
{
/** Chunk k of [begin, end) split into n nearly equal contiguous parts. */
std::pair<int, int> chunk(int begin, int end, unsigned n, unsigned k)
{
  const long len = end - begin;
  return {begin + static_cast<int>(len * k / n), begin + static_cast<int>(len * (k + 1) / n)};
}
}  // namespace

CThreadPool::CThreadPool(unsigned nThreads)
{
  m_nThreads = nThreads ? nThreads : std::max(1u, std::thread::hardware_concurrency());
  for (unsigned i = 1; i < m_nThreads; ++i) m_workers.emplace_back([this, i] { workerLoop(i); });
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

void CThreadPool::workerLoop(unsigned id)
{
  unsigned seen = 0;
  for (;;)
  {
    const std::function<void(int)>* job;
    int b, e;
    {
      std::unique_lock<std::mutex> lk(m_mutex);
      m_cvStart.wait(lk, [&] { return m_stop || m_generation != seen; });
      if (m_stop) return;
      seen = m_generation;
      job = m_job;
      b = m_begin;
      e = m_end;
    }
    std::exception_ptr err;
    try
    {
      const auto [cb, ce] = chunk(b, e, m_nThreads, id);
      for (int i = cb; i < ce; ++i) (*job)(i);
    }
    catch (...)
    {
      err = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lk(m_mutex);
      if (err && !m_error) m_error = err;
      if (--m_pending == 0) m_cvDone.notify_one();
    }
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
  {
    std::lock_guard<std::mutex> lk(m_mutex);
    m_job = &f;
    m_begin = begin;
    m_end = end;
    m_pending = m_nThreads - 1;
    m_error = nullptr;
    ++m_generation;
  }
  m_cvStart.notify_all();
  std::exception_ptr err;
  try
  {
    const auto [cb, ce] = chunk(begin, end, m_nThreads, 0);
    for (int i = cb; i < ce; ++i) f(i);
  }
  catch (...)
  {
    err = std::current_exception();
  }
  std::unique_lock<std::mutex> lk(m_mutex);
  m_cvDone.wait(lk, [&] { return m_pending == 0; });
  if (!err) err = m_error;
  m_job = nullptr;
  if (err) std::rethrow_exception(err);
}
}  // namespace immslam::math
