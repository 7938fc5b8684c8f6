// The export's encoding pool: every job runs exactly once, each output lands in its own slot in
// submission order, the same outputs and the same error whatever the thread count, and the
// reported failure is the lowest-numbered failed job's even when a later job failed first.
// Also run under ThreadSanitizer (test/scripts/test_sanitizers_tsan.sh).
#include "hameritt/dataset/encode_pool.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace hameritt::dataset {
namespace {

// A job's output: a pseudo-random function of its number (splitmix64), costly enough that the
// threads overlap.
std::uint64_t mix(std::uint64_t x) {
  for (int i = 0; i < 200; ++i) {
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    x ^= x >> 31;
  }
  return x;
}

struct FrameError : std::runtime_error {
  FrameError(int f, const std::string& m) : std::runtime_error(m), frame(f) {}
  int frame;
};

// Outputs and run counts of `jobs` jobs on `threads` threads; job k throws FrameError when
// fails(k).
struct PoolRun {
  std::vector<std::uint64_t> out;
  std::vector<int> runs;
  std::string error;  // "" when finish() did not throw
  int error_frame = -1;
};
template <class Fails>
PoolRun runPool(int threads, int jobs, std::size_t capacity, Fails fails) {
  PoolRun r;
  r.out.assign(static_cast<std::size_t>(jobs), 0);
  auto runs = std::make_unique<std::atomic<int>[]>(static_cast<std::size_t>(jobs));
  EncodePool pool(threads, capacity);
  int queued = 0;
  for (int k = 0; k < jobs; ++k) {
    const bool ok = pool.submit([&r, &runs, fails, k] {
      runs[static_cast<std::size_t>(k)]++;
      if (fails(k)) throw FrameError(k, "frame " + std::to_string(k) + " does not decode");
      r.out[static_cast<std::size_t>(k)] = mix(static_cast<std::uint64_t>(k));
    });
    if (!ok) break;
    ++queued;
  }
  EXPECT_EQ(pool.submitted(), static_cast<std::uint64_t>(queued));
  try {
    pool.finish();
  } catch (const FrameError& e) {
    r.error = e.what();
    r.error_frame = e.frame;
  }
  for (int k = 0; k < jobs; ++k) r.runs.push_back(runs[static_cast<std::size_t>(k)].load());
  return r;
}

TEST(EncodePool, RunsEveryJobExactlyOnceWithItsOutputInItsSlot) {
  for (int threads : {1, 2, 3, 8}) {
    for (std::size_t capacity : {std::size_t{1}, std::size_t{4}, std::size_t{64}}) {
      const PoolRun r = runPool(threads, 500, capacity, [](int) { return false; });
      EXPECT_EQ(r.error, "");
      for (int k = 0; k < 500; ++k) {
        ASSERT_EQ(r.runs[static_cast<std::size_t>(k)], 1)
            << "job " << k << ", " << threads << " threads, capacity " << capacity;
        ASSERT_EQ(r.out[static_cast<std::size_t>(k)], mix(static_cast<std::uint64_t>(k)))
            << "job " << k << ", " << threads << " threads";
      }
    }
  }
}

TEST(EncodePool, SameOutputsAndSameErrorWhateverTheThreadCount) {
  const auto fails = [](int k) { return k == 123 || k == 301; };
  const PoolRun one = runPool(1, 400, 2, fails);
  EXPECT_EQ(one.error_frame, 123);
  EXPECT_EQ(one.error, "frame 123 does not decode");
  for (int threads : {2, 4, 8}) {
    const PoolRun r = runPool(threads, 400, 2 * static_cast<std::size_t>(threads), fails);
    EXPECT_EQ(r.error, one.error) << threads << " threads";
    // Every job before the failed one ran once, with the same output; none after ran twice.
    for (int k = 0; k < 400; ++k) {
      if (k <= 123) {
        ASSERT_EQ(r.runs[static_cast<std::size_t>(k)], 1) << "job " << k;
        ASSERT_EQ(r.out[static_cast<std::size_t>(k)], one.out[static_cast<std::size_t>(k)]);
      } else {
        ASSERT_LE(r.runs[static_cast<std::size_t>(k)], 1) << "job " << k;
      }
    }
  }
}

// Job 6 fails first (the main thread sees submit() refuse), then job 5 fails: the error
// reported is job 5's. A pool that kept the first failure in time would report job 6's.
TEST(EncodePool, ReportsTheLowestNumberedFailureNotTheFirstInTime) {
  for (int threads : {2, 4}) {
    EncodePool pool(threads, 4);
    std::atomic<bool> release{false};
    for (int k = 0; k < 5; ++k) ASSERT_TRUE(pool.submit([] {}));
    ASSERT_TRUE(pool.submit([&release] {
      while (!release.load()) std::this_thread::yield();
      throw FrameError(5, "frame 5");
    }));
    ASSERT_TRUE(pool.submit([] { throw FrameError(6, "frame 6"); }));
    // Job 5 holds one thread; another runs job 6, and submit() refuses once it has failed.
    std::uint64_t refused_after = 0;
    while (pool.submit([] {})) ++refused_after;
    EXPECT_EQ(pool.submitted(), 7u + refused_after);
    release = true;
    try {
      pool.finish();
      ADD_FAILURE() << "finish() did not throw";
    } catch (const FrameError& e) {
      EXPECT_EQ(e.frame, 5) << threads << " threads";
    }
  }
}

TEST(EncodePool, PropagatesTheJobsOwnExceptionType) {
  EncodePool pool(2, 2);
  ASSERT_TRUE(pool.submit([] { throw std::out_of_range("row 7 outside the image"); }));
  EXPECT_THROW(
      {
        try {
          pool.finish();
        } catch (const std::out_of_range& e) {
          EXPECT_STREQ(e.what(), "row 7 outside the image");
          throw;
        }
      },
      std::out_of_range);
}

TEST(EncodePool, RejectsNoThreadsOrNoRoom) {
  EXPECT_THROW(EncodePool(0, 4), std::invalid_argument);
  EXPECT_THROW(EncodePool(2, 0), std::invalid_argument);
}

TEST(EncodePool, DestructorWaitsForQueuedJobsAndDropsTheFailure) {
  std::atomic<int> done{0};
  {
    EncodePool pool(3, 8);
    for (int k = 0; k < 50; ++k) {
      ASSERT_TRUE(pool.submit([&done] { done++; }));
    }
  }
  EXPECT_EQ(done.load(), 50);
  EXPECT_NO_THROW({
    EncodePool pool(1, 1);
    pool.submit([] { throw std::runtime_error("dropped"); });
  });
}

}  // namespace
}  // namespace hameritt::dataset
