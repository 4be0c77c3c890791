/* imm-monoslam — a tiny deterministic parallel-for over a persistent pool of worker threads.
 *
 * Work is split into contiguous chunks decided only by (begin, end, number of workers), so results
 * are bitwise identical from run to run whatever the scheduling, as long as each index writes its
 * own outputs. Used where the measurements say it pays (IMM bank, mixing). */
#pragma once

#include <condition_variable>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace immslam::math
{
/** A fixed set of worker threads running parallelFor() jobs; with 1 thread everything runs inline. */
class CThreadPool
{
 public:
  /** \param nThreads total threads used by parallelFor, including the caller (0: hardware concurrency). */
  explicit CThreadPool(unsigned nThreads = 0);
  ~CThreadPool();
  CThreadPool(const CThreadPool&) = delete;
  CThreadPool& operator=(const CThreadPool&) = delete;

  unsigned size() const { return m_nThreads; }

  /** Calls f(i) for every i in [begin, end), split into size() contiguous chunks; the caller runs
   * the first chunk. Blocks until all are done. Exceptions thrown by f are rethrown here (the first). */
  void parallelFor(int begin, int end, const std::function<void(int)>& f);

 private:
  void workerLoop(unsigned id);

  unsigned m_nThreads = 1;
  std::vector<std::thread> m_workers;
  std::mutex m_mutex;
  std::condition_variable m_cvStart, m_cvDone;
  const std::function<void(int)>* m_job = nullptr;
  int m_begin = 0, m_end = 0;
  unsigned m_generation = 0, m_pending = 0;
  bool m_stop = false;
  std::exception_ptr m_error;
};
}  // namespace immslam::math
