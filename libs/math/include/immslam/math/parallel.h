/* imm-monoslam — a tiny deterministic parallel-for over a persistent pool of worker threads.
 *
 * Indices are handed out one at a time from a shared counter (dynamic scheduling: the 7 modes of
 * the IMM bank do not cost the same, a static split of 7 indices over 2 threads left one idle for a
 * third of the time). Results are still bitwise identical from run to run and for any number of
 * threads, because each index computes and writes only its own outputs: which thread runs an index
 * never changes what it computes. Workers spin briefly before sleeping, so the several
 * parallelFor calls of one frame do not each pay a thread wake-up (~40 us measured with a
 * condition variable alone). Used where the measurements say it pays (IMM bank, mixing, search). */
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
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

  /** Calls f(i) once for every i in [begin, end), the caller taking part. Blocks until all are
   * done. Exceptions thrown by f are rethrown here (the first one; the other indices still run).
   * Not reentrant: f must not call parallelFor on the same pool. */
  void parallelFor(int begin, int end, const std::function<void(int)>& f);

 private:
  void workerLoop();
  /** Claims and runs indices of generation gen until none is left. */
  void runIndices(std::uint32_t gen);

  unsigned m_nThreads = 1;
  std::vector<std::thread> m_workers;
  std::mutex m_mutex;
  std::condition_variable m_cvStart, m_cvDone;
  /** (generation << 32) | (index count << 16) | next index offset: claiming an index is one CAS
   * that also checks that the job, and its count, are still the ones the worker woke up for. */
  std::atomic<std::uint64_t> m_ticket{0};
  std::atomic<int> m_done{0};
  const std::function<void(int)>* m_job = nullptr;
  int m_begin = 0;
  std::atomic<bool> m_stop{false};
  std::exception_ptr m_error;
};
}  // namespace immslam::math
