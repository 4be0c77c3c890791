/* imm-monoslam — deterministic parallel-for over mrpt::WorkerThreadsPool (see parallel.h). */
#include <immslam/math/parallel.h>

#include <mrpt/core/WorkerThreadsPool.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <future>
#include <mutex>
#include <thread>
#include <vector>

namespace immslam::math
{
struct CThreadPool::TWorkers
{
  explicit TWorkers(unsigned n) : pool(n, mrpt::WorkerThreadsPool::POLICY_FIFO, "immslam-pool") {}
  mrpt::WorkerThreadsPool pool;
};

CThreadPool::CThreadPool(unsigned nThreads)
    : m_nThreads(nThreads ? nThreads : std::max(1u, std::thread::hardware_concurrency()))
{
  if (m_nThreads > 1) m_workers = std::make_unique<TWorkers>(m_nThreads - 1);
}

CThreadPool::~CThreadPool() = default;

void CThreadPool::parallelFor(int begin, int end, const std::function<void(int)>& f)
{
  if (end <= begin) return;
  // Everything a task touches lives in this call: a task of one call can never see another's. With one
  // thread the caller runs every index itself, the same way (every index runs, the first error is rethrown).
  std::atomic<int> next{begin};
  std::mutex errorMutex;
  std::exception_ptr error;
  const auto claimAndRun = [&] {
    for (int i = next++; i < end; i = next++)
    {
      try
      {
        f(i);
      }
      catch (...)
      {
        std::lock_guard<std::mutex> lk(errorMutex);
        if (!error) error = std::current_exception();
      }
    }
  };
  const int helpers = m_workers ? std::min(static_cast<int>(m_nThreads) - 1, end - begin - 1) : 0;
  std::vector<std::future<void>> done;
  std::exception_ptr enqueueError;  // (out of memory) the tasks already handed out must still be awaited
  try
  {
    done.reserve(static_cast<std::size_t>(helpers));
    for (int k = 0; k < helpers; ++k) done.push_back(m_workers->pool.enqueue(claimAndRun));
  }
  catch (...)
  {
    enqueueError = std::current_exception();
  }
  claimAndRun();
  for (auto& d : done) d.get();  // claimAndRun never throws: get() only waits
  if (error) std::rethrow_exception(error);
  if (enqueueError) std::rethrow_exception(enqueueError);
}
}  // namespace immslam::math
