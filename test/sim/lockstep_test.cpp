#include "hameritt/sim/lockstep.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace hameritt::sim {
namespace {

TEST(PublicationCounter, CountsPerTopicFromManyThreads) {
  PublicationCounter c;
  std::vector<std::thread> threads;
  for (int k = 0; k < 4; ++k) {
    threads.emplace_back([&c, k] {
      for (int i = 0; i < 1000; ++i) c.add(k % 2 ? "/b" : "/a");
    });
  }
  for (auto& t : threads) t.join();
  c.add("/c", 5);
  const auto counts = c.counts();
  ASSERT_EQ(counts.size(), 3u);
  EXPECT_EQ(counts[0], std::make_pair(std::string("/a"), std::uint64_t{2000}));
  EXPECT_EQ(counts[1], std::make_pair(std::string("/b"), std::uint64_t{2000}));
  EXPECT_EQ(counts[2], std::make_pair(std::string("/c"), std::uint64_t{5}));
}

TEST(LockstepTally, KeepsTheLatestCumulativeCountsAndRefusesGoingBack) {
  LockstepTally t;
  t.update("/sim", {{"/odom", 5}, {"/clock", 5}});
  t.update("/planner", {{"/cmd", 1}});
  t.update("/sim", {{"/odom", 10}});
  const auto s = t.streams();
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].topic, "/clock");
  EXPECT_EQ(s[0].count, 5u);
  EXPECT_EQ(s[1].topic, "/cmd");
  EXPECT_EQ(s[1].publisher, "/planner");
  EXPECT_EQ(s[2].topic, "/odom");
  EXPECT_EQ(s[2].count, 10u);
  try {
    t.update("/sim", {{"/odom", 9}});
    FAIL() << "a count going back was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/odom"), std::string::npos) << e.what();
  }
}

TEST(LockstepInbox, MissingNamesTheShortStreamsOfItsOwnTopicsOnly) {
  LockstepInbox in;
  const std::size_t odom = in.addSubscription("/odom");
  in.addSubscription("/waypoints");
  const std::vector<StreamCount> totals = {
      {"/odom", "/sim", 3}, {"/waypoints", "/client", 1}, {"/other", "/sim", 7}};
  auto m = in.missing(totals);
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].topic, "/odom");
  EXPECT_EQ(m[0].count, 3u);
  for (int i = 0; i < 3; ++i) in.receive(odom, "/sim", [] {});
  m = in.missing(totals);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].topic, "/waypoints");
  EXPECT_EQ(m[0].publisher, "/client");
  // More than published (a publisher outside the lock-step) is not missing anything.
  in.receive(1, "/client", [] {});
  in.receive(1, "/client", [] {});
  EXPECT_TRUE(in.missing(totals).empty());
  EXPECT_EQ(in.pending(), 5u);
  EXPECT_THROW(in.receive(9, "/sim", [] {}), std::out_of_range);
}

// The order handed out does not depend on the order of arrival across topics and publishers.
TEST(LockstepInbox, TakeIsCanonicalWhateverTheArrivalOrder) {
  const std::vector<std::string> order = {"/sim", "/detector", "/adk"};
  struct Msg {
    std::size_t sub;
    std::string publisher;
    int seq;  // per (sub, publisher): the publisher's order
  };
  std::vector<Msg> msgs;
  const std::vector<std::string> publishers = {"/adk", "/sim", "/detector", "/zeta", "/alpha"};
  for (std::size_t sub = 0; sub < 3; ++sub) {
    for (const auto& p : publishers) {
      for (int s = 0; s < 4; ++s) msgs.push_back({sub, p, s});
    }
  }
  std::vector<std::string> reference;
  std::mt19937 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    // A random interleaving that keeps each stream's own order (per-connection FIFO).
    std::vector<Msg> arrival;
    std::vector<std::vector<Msg>> streams;
    for (std::size_t i = 0; i < msgs.size(); i += 4) {
      streams.emplace_back(msgs.begin() + static_cast<long>(i),
                           msgs.begin() + static_cast<long>(i + 4));
    }
    while (!streams.empty()) {
      const std::size_t k = std::uniform_int_distribution<std::size_t>(0, streams.size() - 1)(rng);
      arrival.push_back(streams[k].front());
      streams[k].erase(streams[k].begin());
      if (streams[k].empty()) streams.erase(streams.begin() + static_cast<long>(k));
    }
    LockstepInbox in;
    for (int s = 0; s < 3; ++s) in.addSubscription("/t" + std::to_string(s));
    std::vector<std::string> got;
    for (const auto& m : arrival) {
      const std::string tag =
          m.publisher + "/t" + std::to_string(m.sub) + "#" + std::to_string(m.seq);
      in.receive(m.sub, m.publisher, [&got, tag] { got.push_back(tag); });
    }
    for (auto& f : in.take(order)) f();
    EXPECT_EQ(in.pending(), 0u);
    ASSERT_EQ(got.size(), msgs.size());
    if (trial == 0) {
      reference = got;
      // Listed publishers in turn order, then the others by name; subscriptions in order.
      EXPECT_EQ(got.front(), "/sim/t0#0");
      EXPECT_EQ(got[12], "/detector/t0#0");
      EXPECT_EQ(got[24], "/adk/t0#0");
      EXPECT_EQ(got[36], "/alpha/t0#0");
      EXPECT_EQ(got.back(), "/zeta/t2#3");
    } else {
      EXPECT_EQ(got, reference) << "trial " << trial;
    }
  }
}

// Messages arrive on ROS callback threads: one thread per publisher, while the participant polls
// missing() and pending() for its turn. The turn starts once nothing is missing, and take()
// hands out the same order as a single-threaded inbox. Also run under ThreadSanitizer
// (test/scripts/test_sanitizers_tsan.sh).
TEST(LockstepInbox, ReceivesFromManyThreadsWhileTheTurnWaits) {
  const std::vector<std::string> order = {"/sim", "/detector", "/adk"};
  const std::vector<std::string> publishers = {"/adk", "/sim", "/detector", "/zeta", "/alpha"};
  constexpr int kPerStream = 200;
  std::vector<StreamCount> totals;
  for (int sub = 0; sub < 3; ++sub) {
    for (const auto& p : publishers) totals.push_back({"/t" + std::to_string(sub), p, kPerStream});
  }
  auto tagOf = [](const std::string& p, int sub, int seq) {
    return p + "/t" + std::to_string(sub) + "#" + std::to_string(seq);
  };
  // The reference: every message from one thread.
  std::vector<std::string> reference;
  {
    LockstepInbox in;
    for (int s = 0; s < 3; ++s) in.addSubscription("/t" + std::to_string(s));
    for (const auto& p : publishers) {
      for (int seq = 0; seq < kPerStream; ++seq) {
        for (int sub = 0; sub < 3; ++sub) {
          const std::string tag = tagOf(p, sub, seq);
          in.receive(static_cast<std::size_t>(sub), p,
                     [&reference, tag] { reference.push_back(tag); });
        }
      }
    }
    for (auto& f : in.take(order)) f();
  }
  ASSERT_EQ(reference.size(), 3u * publishers.size() * kPerStream);

  LockstepInbox in;
  for (int s = 0; s < 3; ++s) in.addSubscription("/t" + std::to_string(s));
  std::vector<std::string> got;
  std::vector<std::thread> threads;
  for (const auto& p : publishers) {
    threads.emplace_back([&in, &got, &tagOf, p] {
      for (int seq = 0; seq < kPerStream; ++seq) {
        for (int sub = 0; sub < 3; ++sub) {
          const std::string tag = tagOf(p, sub, seq);
          in.receive(static_cast<std::size_t>(sub), p, [&got, tag] { got.push_back(tag); });
        }
      }
    });
  }
  std::size_t polls = 0;
  while (!in.missing(totals).empty()) {
    EXPECT_LE(in.pending(), reference.size());
    ++polls;
    std::this_thread::yield();
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(in.pending(), reference.size());
  for (auto& f : in.take(order)) f();
  EXPECT_EQ(in.pending(), 0u);
  EXPECT_EQ(got, reference) << "after " << polls << " polls";
}

TEST(PeriodicSchedule, DueOncePerPeriodAtTheFirstTurnAtOrAfterEachMultiple) {
  PeriodicSchedule p(0.1);
  std::vector<double> fired;
  // Turns every 0.02 s, accumulated the way a simulator adds its steps.
  double t = 0.0;
  for (int i = 0; i < 50; ++i) {
    t += 0.002 * 10;
    if (p.due(t)) fired.push_back(t);
  }
  ASSERT_EQ(fired.size(), 10u);
  for (std::size_t i = 0; i < fired.size(); ++i) EXPECT_NEAR(fired[i], 0.1 * (i + 1), 1e-9);
  // A turn that passes several multiples runs the work once.
  PeriodicSchedule q(0.1);
  EXPECT_FALSE(q.due(0.05));
  EXPECT_TRUE(q.due(0.35));
  EXPECT_FALSE(q.due(0.39));
  EXPECT_TRUE(q.due(0.4));
  EXPECT_THROW(PeriodicSchedule(0.0), std::invalid_argument);
  EXPECT_THROW(PeriodicSchedule(std::nan("")), std::invalid_argument);
}

}  // namespace
}  // namespace hameritt::sim
