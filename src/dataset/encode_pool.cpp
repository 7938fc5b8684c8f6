#include "hameritt/dataset/encode_pool.h"

#include <stdexcept>
#include <string>

namespace hameritt::dataset {

EncodePool::EncodePool(int threads, std::size_t capacity) : capacity_(capacity) {
  if (threads < 1) {
    throw std::invalid_argument("EncodePool: threads must be at least 1, got " +
                                std::to_string(threads));
  }
  if (capacity < 1) throw std::invalid_argument("EncodePool: capacity must be at least 1, got 0");
  threads_.reserve(static_cast<std::size_t>(threads));
  for (int i = 0; i < threads; ++i) threads_.emplace_back([this] { work(); });
}

EncodePool::~EncodePool() { join(); }

bool EncodePool::submit(std::function<void()> job) {
  std::unique_lock<std::mutex> lock(mutex_);
  space_ready_.wait(lock, [this] { return queue_.size() < capacity_ || failure_; });
  if (failure_ || stop_) return false;
  queue_.push_back(Job{submitted_++, std::move(job)});
  work_ready_.notify_one();
  return true;
}

void EncodePool::finish() {
  join();
  std::lock_guard<std::mutex> lock(mutex_);
  if (failure_) std::rethrow_exception(failure_);
}

std::uint64_t EncodePool::submitted() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return submitted_;
}

void EncodePool::join() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  work_ready_.notify_all();
  space_ready_.notify_all();
  for (auto& t : threads_) {
    if (t.joinable()) t.join();
  }
}

void EncodePool::work() {
  while (true) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      work_ready_.wait(lock, [this] { return !queue_.empty() || stop_; });
      if (queue_.empty()) return;
      job = std::move(queue_.front());
      queue_.pop_front();
      space_ready_.notify_one();
      // A job after a failed one is skipped: its output would be thrown away.
      if (job.number > failed_job_) continue;
    }
    try {
      job.run();
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      if (job.number < failed_job_) {
        failed_job_ = job.number;
        failure_ = std::current_exception();
      }
      space_ready_.notify_all();  // a waiting submit() returns false
    }
  }
}

}  // namespace hameritt::dataset
