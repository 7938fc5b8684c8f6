#pragma once
// The thread pool that encodes an export's frames (hameritt_export --jobs N): a fixed number of
// threads and a bounded queue, so that a long bag never holds more than `capacity` frames in
// memory while the encoders catch up. Jobs are numbered in the order they are submitted and each
// writes only its own output, so the result does not depend on the thread count. Errors are
// deterministic too: the failure reported is that of the lowest-numbered failed job, whatever
// the timing (jobs after a failed one are skipped, jobs before it still run).

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <exception>
#include <functional>
#include <limits>
#include <mutex>
#include <thread>
#include <vector>

namespace hameritt::dataset {

class EncodePool {
 public:
  // Starts `threads` threads (at least 1) with room for `capacity` queued jobs (at least 1);
  // throws std::invalid_argument otherwise.
  EncodePool(int threads, std::size_t capacity);
  // Waits for the queued jobs and joins the threads; a failure is dropped (call finish() to see
  // it).
  ~EncodePool();
  EncodePool(const EncodePool&) = delete;
  EncodePool& operator=(const EncodePool&) = delete;

  // Queues the next job, waiting while the queue is full. Returns false, and queues nothing,
  // once a job has failed: finish() then reports the failure.
  bool submit(std::function<void()> job);
  // Waits for every queued job and joins the threads, then rethrows the exception of the
  // lowest-numbered job that threw, if any. No job may be submitted after it.
  void finish();
  // How many jobs submit() has queued.
  std::uint64_t submitted() const;

 private:
  struct Job {
    std::uint64_t number = 0;
    std::function<void()> run;
  };
  static constexpr std::uint64_t kNoFailure = std::numeric_limits<std::uint64_t>::max();

  void work();
  void join();

  std::size_t capacity_;
  std::vector<std::thread> threads_;
  mutable std::mutex mutex_;
  std::condition_variable work_ready_, space_ready_;
  std::deque<Job> queue_;
  std::uint64_t submitted_ = 0;
  bool stop_ = false;
  std::uint64_t failed_job_ = kNoFailure;  // the lowest-numbered job that threw
  std::exception_ptr failure_;             // its exception
};

}  // namespace hameritt::dataset
