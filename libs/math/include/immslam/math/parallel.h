/* imm-monoslam — a deterministic parallel-for over MRPT's thread pool (mrpt::WorkerThreadsPool).
 *
 * CThreadPool holds an mrpt::WorkerThreadsPool of num_threads - 1 threads. parallelFor(begin, end, f)
 * hands it up to num_threads - 1 helper tasks and runs one more on the caller; every one takes the
 * next index from a counter of its own call until none is left (dynamic scheduling: the 7 modes of
 * the IMM bank do not cost the same, a static split of 7 indices over 2 threads left one idle for a
 * third of the time), and the caller waits for the helpers' futures. Results are bitwise identical
 * from run to run and for any number of threads, because each index computes and writes only its own
 * outputs: which thread runs an index never changes what it computes.
 *
 * Why MRPT's pool (doc/experiments/performance.md, "The thread pool", has the figures and commands):
 * against the spinning pool written here before, median frame time ratio 1.00 (perf-report.sh --quick,
 * every config and sequence) and 0.93 (400-frame bench_system runs) on a shared 2-core machine; oneTBB
 * (tbb::parallel_for in a task_arena) 0.92, OpenMP (libgomp) 1.1-20 x slower. MRPT is already the
 * project's base: no new dependency. Its cost is a thread wake-up per call (10-100 us on that loaded
 * machine), a few calls per frame. */
#pragma once

#include <functional>
#include <memory>

namespace immslam::math
{
/** A fixed number of threads for parallelFor() jobs ([slam] num_threads); with 1 thread everything
 * runs inline on the caller. */
class CThreadPool
{
 public:
  /** \param nThreads threads used by parallelFor, the caller included (0: hardware concurrency). */
  explicit CThreadPool(unsigned nThreads = 0);
  ~CThreadPool();
  CThreadPool(const CThreadPool&) = delete;
  CThreadPool& operator=(const CThreadPool&) = delete;

  unsigned size() const { return m_nThreads; }

  /** Calls f(i) once for every i in [begin, end), the caller taking part. Blocks until all are
   * done. Every index runs; the first exception thrown by f is then rethrown here.
   * Not reentrant: f must not call parallelFor on the same pool. */
  void parallelFor(int begin, int end, const std::function<void(int)>& f);

 private:
  struct TWorkers;  ///< the mrpt::WorkerThreadsPool (parallel.cpp: keeps MRPT's header out of this one)
  unsigned m_nThreads = 1;
  std::unique_ptr<TWorkers> m_workers;  ///< null with one thread
};
}  // namespace immslam::math
